import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
CASES = ROOT / "cases"
sys.path.insert(0, str(Path(__file__).resolve().parent))

# The `numeric` marker (pyproject.toml): a test whose outcome can depend on the floating-point
# kernels (BLAS/LAPACK: OpenBLAS picks one per processor, OPENBLAS_CORETYPE forces another).
# CI runs these a second time under another kernel (.ci/run), so that a tolerance taken from
# what one machine printed fails there and not for a user.  Every test is numeric unless it is
# named below with the reason its assertions cannot depend on a kernel: a new test is covered
# by default.  Whole modules:
NOT_NUMERIC_MODULES = {
    "test_layers.py": "import contracts, cycles and call counts of the parser",
    "test_lint.py": "the linter on the source text",
    "test_no_probing.py": "a scan of the source text",
    "test_packaging.py": "the package list and the bundled files",
    "test_names.py": "string labels",
    "test_expr.py": "the expression whitelist: Python floats and refusals, no array kernel",
    "test_urdf_errors.py": "one-line refusals of files that cannot be read",
    "test_report_browser.py": "the page's animations render and move (pixels change)",
    "test_fuzz.py": "mutated inputs: exit code 0 or 2, one line, no traceback, no file touched",
    "test_resume.py": "a resumed sweep equals the uninterrupted one: one kernel, twice",
    "test_interrupt.py": "signals, exit codes, the one line, and an interrupted sweep resumed "
                         "equal to the uninterrupted one: one kernel, twice",
}
# single tests in modules that are otherwise numeric (the test's name, parameters left off)
NOT_NUMERIC_TESTS = {
    "test_report.py": {"test_report_is_deterministic": "the same report twice, byte for byte"},
    "test_library.py": {"test_unreachable_scheduler_one_line_exit_2": "a refusal"},
    "test_plots.py": {"test_plots_do_not_switch_the_backend": "matplotlib's backend"},
    "test_bench.py": {"test_bench_startup_rows_follow_the_method": "how the start-up rows are "
                      "measured (pairs, the floor, the environment), no time"},
}


def pytest_configure(config):
    """A name in the lists above that no longer exists would leave its successor out of the
    second pass silently: refuse it instead."""
    here = Path(__file__).resolve().parent
    for module in (*NOT_NUMERIC_MODULES, *NOT_NUMERIC_TESTS):
        if not (here / module).is_file():
            raise pytest.UsageError(f"tests/conftest.py: no tests/{module} (NOT_NUMERIC lists)")
    for module, tests in NOT_NUMERIC_TESTS.items():
        text = (here / module).read_text()
        for name in tests:
            if f"def {name}(" not in text:
                raise pytest.UsageError(f"tests/conftest.py: no {name} in tests/{module}")


def pytest_collection_modifyitems(config, items):
    for item in items:
        if item.path.name in NOT_NUMERIC_MODULES:
            continue
        if item.originalname in NOT_NUMERIC_TESTS.get(item.path.name, {}):
            continue
        item.add_marker(pytest.mark.numeric)


@pytest.fixture
def cases_dir():
    return CASES


def write_case(tmp_path, text, name="case.toml"):
    """Write a case file for a test and return its path."""
    p = tmp_path / name
    p.write_text(text)
    return p
