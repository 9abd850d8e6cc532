"""Run the full benchmark (the same as ``mbseig bench``); pass ``--quick`` for small sizes.

    python benchmarks/run_bench.py [--quick] [--threads 1] [--sections dense partial ...]

Results: reports/benchmarks.md, reports/benchmarks.json, reports/speed_accuracy.png.
Benchmarks are never part of the test suite; tests/test_bench.py only smoke-tests --quick on tiny
sections.
"""

import sys

from mbseig.cli import main

if __name__ == "__main__":
    sys.exit(main(["bench", *sys.argv[1:]]))
