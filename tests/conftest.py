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
    "test_uncertainty_methods.py": "the statistics of analytic functions of the inputs (no model, "
                                   "no eigenvalue) at tolerances of standard errors and 1e-3 to "
                                   "1e-5, far above any kernel's rounding",
}
# single tests in modules that are otherwise numeric (the test's name, parameters left off)
NOT_NUMERIC_TESTS = {
    "test_beams3d_quartic.py": {
        "test_campbell_one_build_equals_builds_per_point_with_quartic_shafts": "two paths "
        "through the same arithmetic compared for equality: equal under any kernel or neither",
        "test_element_field": "the record's names and counts, a one-line refusal",
        "test_euler_bernoulli_quartic_refused_and_auto_defaults": "refusals and the element "
        "the record names"},
    "test_check_beams3d.py": {
        "test_a_singular_solve_inside_the_integrator_is_a_simulation_error": "the error raised "
        "by a forced failing solve"},
    "test_periodic_descriptor.py": {
        "test_partial_on_request_says_so": "which method answers and the text that says so"},
    "test_campbell_reuse.py": {
        "test_one_build_gives_the_full_builds_numbers": "two paths through the same arithmetic "
        "compared for equality, byte for byte: equal under any kernel or neither",
        "test_speed_update_declines_a_speed_elsewhere": "where a parameter enters the case text"},
    "test_local_basis.py": {
        "test_shaft_on_universal_joints_is_the_standard_fe_problem": "counts of triads, "
        "components and columns, and which entries of N are nonzero (exact at the reference)"},
    "test_report.py": {"test_report_is_deterministic": "the same report twice, byte for byte",
                       "test_report_sections_and_time_domain_check": "headings, the commanded "
                       "posture, the time-domain check's percent-level pass, the sensitivity "
                       "ranking's first parameter and its unit",
                       "test_report_summary_names_units_provenance": "headings, names, units "
                       "and provenance of the page (its numbers: tests/test_cases.py)"},
    # the output's schema and the verdict rule over whatever modes a case lists: no value against
    # a reference (every case's values: tests/test_cases.py and test_small_modes.py, numeric)
    "test_cli.py": {"test_modes_json_schema": "the JSON's keys, order and verdict rule",
                    "test_executable_prompt_exit_delivers_the_whole_output": "a process's "
                    "output equals main()'s in the same kernel, exit codes",
                    "test_modes_table_and_linearize": "the table's labels, files written"},
    "test_report_reading.py": {
        "test_one_page_style_for_every_motion": "the page's style sheet and layout",
        "test_bicycle_report_has_figures_and_units": "figures embedded, units named",
        "test_no_report_names_an_internal_coordinate": "names in the text",
        "test_no_text_is_clipped": "a figure's text inside its canvas",
        "test_periodic_multiplier_figure_is_not_clipped": "a figure's text inside its canvas",
        "test_gif_text_is_legible_and_a_rotor_shows_both_lateral_directions": "legibility and "
        "what a frame shows"},
    "test_unbalance.py": {
        "test_report_rotor_section_from_the_command_line": "the section's headings and names",
        "test_report_study_names_its_unbalance": "names in the text",
        "test_unbalance_table_names_stations_as_the_case_does": "names in the table"},
    "test_flexible3d_commands.py": {"test_beams_are_drawn_as_curves": "the drawing's lines",
                                    "test_report_on_a_3d_flexible_rotor": "sections, figures, "
                                    "and ω = Ω read from the printed 6 digits to 1e-5"},
    # an integration's error against a prediction at 1 %: another kernel's rounding (1e-15
    # relative) cannot move it (the rounding-level tests of that module stay numeric)
    "test_timedomain.py": {"test_damped_chain_every_mode_within_1_percent": "1 % tolerance",
                           "test_cli_json_schema": "the JSON's keys and the tolerances it "
                           "records"},
    "test_beams3d.py": {"test_bad_input_one_line": "one-line refusals"},
    "test_bad_input.py": {"test_real_process_exit_code": "an exit code and one line"},
    "test_periodic_report.py": {"test_periodic_report_no_check_no_studies": "sections left out "
                                "and a refusal"},
    "test_spatial_cli.py": {"test_report_on_every_spatial_case": "the report is written (the "
                            "verdict it prints: test_modes_and_check_on_every_spatial_case)"},
    # the probabilities of instability against closed forms, within standard errors (or 1e-3
    # for FORM): a kernel's rounding moves no sample's verdict across δ = 0 unless its δ lies
    # within ~1e-13 of it (the verdict rule and its bounds stay numeric: test_batch_rules.py,
    # test_cases.py, and here the batch against one sample at a time)
    "test_uncertainty.py": {"test_resume_gives_the_same_output": "a resumed study equals the "
                            "uninterrupted one: one kernel, twice",
                            "test_bad_inputs_are_refused_in_one_line": "one-line refusals",
                            "test_monte_carlo_matches_the_closed_form": "standard errors",
                            "test_zero_unstable_samples_give_an_honest_interval": "no sample "
                            "near the boundary",
                            "test_form_is_exact_on_the_plane": "1e-3",
                            "test_form_beta_is_negative_where_the_mean_is_unstable": "1e-3",
                            "test_subset_simulation_reaches_a_small_probability": "3 CoV",
                            "test_flutter_of_the_damped_ziegler_pendulum": "1e-3 and standard "
                            "errors",
                            "test_samples_without_a_model_are_counted_failed": "counts and "
                            "messages",
                            "test_readme_worked_example": "the README's 3 printed digits"},
    "test_guide.py": {"test_every_block_of_the_guide_runs": "the guide's commands exit 0 and "
                      "write their files"},
    "test_animate.py": {"test_report_embeds_one_animation_per_mode": "one animation a mode",
                        "test_cli_writes_a_looping_gif_of_one_period": "the file's frames, loop"},
    "test_library.py": {"test_unreachable_scheduler_one_line_exit_2": "a refusal"},
    "test_periodic_frames.py": {
        "test_a_body_on_a_moving_basic_point_is_refused": "a one-line refusal",
        "test_a_joint_moving_between_two_bodies_or_turning_is_refused": "one-line refusals"},
    "test_plots.py": {"test_plots_do_not_switch_the_backend": "matplotlib's backend",
                      "test_pole_map_grid_and_legend_outside": "layout",
                      "test_decade_scale": "the axis' ticks"},
    "test_bench.py": {"test_bench_startup_rows_follow_the_method": "how the start-up rows are "
                      "measured (pairs, the floor, the environment), no time",
                      "test_bench_quick_writes_report": "the report's rows and files, no time",
                      "test_bench_quick_large_section": "the section's rows, no time"},
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
