"""``mbseig bench``: speed against accuracy of every solver path, measured side by side.

- :mod:`~mbseig.bench.run`: the measurements (:func:`run_bench`);
- :mod:`~mbseig.bench.report`: reports/benchmarks.md and speed_accuracy.png;
- :mod:`~mbseig.bench.failcases`: where naive methods give the wrong verdict;
- :mod:`~mbseig.bench.cases`: the bundled cases, found in the installed package.
"""

from .run import run_bench

__all__ = ["run_bench"]
