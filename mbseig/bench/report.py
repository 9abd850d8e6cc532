"""reports/benchmarks.md and reports/speed_accuracy.png from a :func:`mbseig.bench.run_bench`
result (the chart is drawn by :func:`mbseig.plots.speed_accuracy`)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .. import plots
from .peer import peer_lines
from .slepc_rows import slepc_targets
from .startup_rows import startup_lines

__all__ = ["write_report"]


def _f(x, fmt=".3g"):
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "–"
    return format(x, fmt)


def _seconds(x):
    return _f(x) + (" s" if isinstance(x, (int, float)) and math.isfinite(x) else "")


def _rows(res, section):
    return [r for r in res["rows"] if r["section"] == section]


def _get(rows, method, n):
    for r in rows:
        if r["method"] == method and r["n"] == n:
            return r
    return None


# small case → the peer model that is the same system (same eigenvalues; the bundled spherical
# pendulum has no pivot damping, the peer's has: not compared)
SMALL_PEER = {"spatial_double_pendulum": "spatial double pendulum"}


def _targets(res):
    out = []
    dense = _rows(res, "dense")
    fl, co = _get(dense, "LAPACK geev (floor)", 1000), _get(dense, "mbseig companion", 1000)
    if fl and co:
        ratio = co["time"] / fl["time"]
        out.append(("dense damped n = 1000, all modes with vectors: mbseig companion / geev floor",
                    f"{ratio:.2f} ({co['time']:.2f} s / {fl['time']:.2f} s)", "≤ 1.1",
                    ratio <= 1.1))
    for r in _rows(res, "structured"):
        if r["n"] == 1000 and "floor_ratio" in r:
            out.append((f"{r['method']} n = 1000, all modes with vectors / eigh(Q, M) with "
                        "vectors",
                        f"{r['floor_ratio']:.2f} ({r['time']:.3f} s / {r['floor_time']:.3f} s)",
                        "≤ 1.15", r["floor_ratio"] <= 1.15))
    for r in _rows(res, "structured"):
        if r["n"] == 600 and "pipeline_ratio" in r:
            out.append(("whole pipeline on the damped chain n = 600 (build, equilibrium and its "
                        "static stability, linearization, modes) / eigh(K, M) on its matrices",
                        f"{r['pipeline_ratio']:.2f} ({r['time']:.3f} s / {r['floor_time']:.3f} s)",
                        "≤ 1.25", r["pipeline_ratio"] <= 1.25))
    for r in _rows(res, "structured"):
        if r["n"] == 3000 and "speedup" in r:
            out.append((f"{r['method']} n = 3000 vs dense general path", f"{r['speedup']:.0f}× "
                        f"({r['time']:.2f} s vs {r['general_time']:.1f} s)", "≥ 20×",
                        r["speedup"] >= 20))
    part = [r for r in _rows(res, "partial") if r["method"] == "partial proportional"]
    big = [r for r in part if r["n"] == 1_000_000]
    if big:
        r = big[0]
        out.append(("lowest 20 modes, damped chain, 10⁶ coordinates (whole pipeline)",
                    f"{r['total']:.1f} s, {r['rss_mb'] / 1024:.2f} GB", "< 60 s, < 4 GB",
                    r["total"] < 60 and r["rss_mb"] < 4096))
    if len(part) >= 2:
        a, b = part[0], part[-1]
        for key in ("total", "modes"):
            # least-squares slope of log t against log n over every size (medians), which one
            # noisy end point cannot swing as it swings the ratio of the two end points
            logn = np.log([r["n"] for r in part])
            logt = np.log([r[key] for r in part])
            p = float(np.polyfit(logn, logt, 1)[0])
            p2 = math.log(b[key] / a[key]) / math.log(b["n"] / a["n"])
            out.append((f"growth of the {key} time, n = {a['n']:.0e} … {b['n']:.0e} "
                        f"(least-squares slope over {len(part)} sizes; end points alone "
                        f"n^{p2:.2f})",
                        f"n^{p:.2f}", "≤ n^1.15", p <= 1.15))
    large = _rows(res, "large")
    big = {r["method"]: r for r in large if r["n"] == 1_000_000}
    for kind in ("partial-projected", "partial-companion", "partial-slepc"):
        if kind in big:
            r = big[kind]
            out.append(("lowest 20 modes, 10⁶ coordinates, 10⁵ constraints, general damping "
                        f"({kind}, eigen stage)",
                        f"{r['time']:.0f} s, {r['rss_mb'] / 1024:.2f} GB, "
                        f"{r['ratio']:.1f}× the eigsh floor", "< 60 s, < 4 GB, ≤ 3×",
                        r["time"] < 60 and r["rss_mb"] < 4096 and r["ratio"] <= 3))
    sizes = sorted({r["n"] for r in large})
    if len(sizes) >= 2:
        for kind in ("partial-projected", "partial-companion", "partial-slepc"):
            pts = sorted((r["n"], r["time"]) for r in large if r["method"] == kind)
            if len(pts) >= 2:
                p = float(np.polyfit(np.log([a for a, _ in pts]), np.log([b for _, b in pts]),
                                     1)[0])
                out.append((f"growth of the general partial path ({kind}), n = {pts[0][0]:.0e} … "
                            f"{pts[-1][0]:.0e}", f"n^{p:.2f}", "≤ n^1.15", p <= 1.15))
    sw = {r["method"]: r for r in _rows(res, "sweeps") if r.get("workers") == 1}
    for key, what in (("in-process", "device sweep (k_a)"),
                      ("in-process, C4 load f × c_a (command reused)", "C4 load sweep (f)")):
        if key in sw:
            r = sw[key]
            extra = f" ({r['vs_general']:.2f}× the general path)" if "vs_general" in r else ""
            out.append((f"{what}, points a second on one core (after the first)",
                        f"{r['rate']:.1f}{extra}", "≥ 300", r["rate"] >= 300))
    peer = {r["model"]: r for r in _rows(res, "peer") if r.get("spatial")}
    for r in _rows(res, "small"):  # the whole from the parsed case against the peer's eigen call
        pr = peer.get(SMALL_PEER.get(r["method"]))
        if pr:
            ratio = r["time"] / pr["exudyn_time"]
            out.append((f"small model {r['method']}: build + equilibrium + linearize + modes / "
                        f"EXUDYN's eigen call on the same system",
                        f"{ratio:.1f} ({r['time'] * 1e3:.2f} ms / "
                        f"{pr['exudyn_time'] * 1e3:.2f} ms)",
                        "≤ 1.0", ratio <= 1.0))
    out += slepc_targets(_rows(res, "slepc"))
    for r in _rows(res, "spatial"):
        if r["n"] >= 10_000:
            out.append((f"{r['n']} spatial bodies on bushings: read + assembled (and the first "
                        "Φ, Φ_q, g, K, C)", f"{r['time']:.2f} s ({r['time'] / r['floor']:.0f}× "
                        "the tomllib + CSR floor)", "≤ 5 s", r["time"] <= 5.0))
    su = {r["method"]: r for r in _rows(res, "startup")}
    for k, r in su.items():
        if k.startswith("mbseig modes") and not k.endswith("normal exit"):
            spread = (f"; pairs {r['ratio_min']:.2f}–{r['ratio_max']:.2f}, cpu {r['cpu_ratio']:.2f}"
                      if "cpu_ratio" in r else "")
            out.append((f"start-up: `{k}` / `python -c \"import numpy, scipy.linalg\"`",
                        f"{r['ratio']:.2f} ({r['time']:.2f} s{spread})", "≤ 1.25",
                        r["ratio"] <= 1.25))
    etas = [r.get("eta", math.nan) for r in res["rows"]
            if r["section"] in ("dense", "structured", "partial")
            and r["method"].startswith(("mbseig", "partial"))]
    etas = [e for e in etas if isinstance(e, float) and math.isfinite(e)]
    if etas:
        out.append(("largest backward error, mbseig paths on chain families", f"{max(etas):.1e}",
                    "≤ 1e-12", max(etas) <= 1e-12))
    return out


def _nlevp_lines(rows):
    """Section "NLEVP quadratic eigenproblems": one row per problem of mbseig/bench/nlevp.py."""
    if not rows:
        return []
    cols = ("problem", "n", "verdict", "reference verdict", "solver", "listed", "infinite",
            "max η", "time", "refusal")
    out = ["", "## NLEVP quadratic eigenproblems (built from the collection's definitions)", "",
           "Each problem through `mbseig.modes` (mbseig/bench/nlevp.py): the verdict against the "
           "reference's, the path, the largest backward error of the listed modes, or the one-line "
           "refusal where double precision cannot resolve the problem.", ""]
    out.append("| " + " | ".join(cols) + " |")
    out.append("|" + "---|" * len(cols))
    for r in rows:
        cells = (r["method"], r["n"], r["verdict"], f"{r['expected']} ({r['reference']})",
                 r["solver"], r["n_listed"], r["n_infinite"], _f(r["eta"], ".1e"),
                 f"{r['time']:.3f} s", r["refused"] or "–")
        out.append("| " + " | ".join(str(c) for c in cells) + " |")
    return out


def _table(L, title, intro, header, rows, row):
    """A section: title, intro paragraph, a table with one line per row (``row(r)``)."""
    L += ["", f"## {title}", "", intro, "", header, "|" + "---|" * (header.count("|") - 1)]
    L.extend(row(r) for r in rows)


def _spatial_line(r):
    cells = [r["method"], r["coordinates"], _seconds(r["stages"]["read + assemble"]),
             _seconds(r["stages"]["first Φ, Φ_q, g, K, C"]), _seconds(r["floor"]), r["repeats"]]
    return "| " + " | ".join(str(c) for c in cells) + " |"


def _load_words(res):
    """' Load average (1, 5, 15 min): … at the start, … at the end.' (empty where not recorded)."""
    load = res.get("load") or {}
    said = [f"{', '.join(f'{x:.2f}' for x in load[k])} at the {k}" for k in ("start", "end")
            if load.get(k)]
    return f" Load average (1, 5, 15 min): {' and '.join(said)}." if said else ""


def write_report(res, out_dir):
    out_dir = Path(out_dir)
    cfg = res["config"]
    L = ["# mbseig benchmarks: speed against accuracy", ""]
    L.append(f"Generated by `mbseig bench{' --quick' if cfg['quick'] else ''}` "
             f"(median of {cfg['repeats']} interleaved runs per point unless stated; BLAS threads: "
             f"{cfg['threads'] or 'library default'}; total {res.get('elapsed', 0):.0f} s). "
             "Machine: "
             f"{res['machine']['cpus']} CPUs, Python {res['machine']['python']}, numpy "
             f"{res['machine']['numpy']}, scipy {res['machine']['scipy']}.{_load_words(res)} The "
             f"machine is shared and noisy: compare ratios measured in the same run, not absolute "
             f"times across runs.")
    L += ["", "![error against wall time](speed_accuracy.png)", "", "## Targets", "",
          "| target | measured | goal | met |", "|---|---|---|---|"]
    for name, val, goal, ok in _targets(res):
        L.append(f"| {name} | {val} | {goal} | {'yes' if ok else '**no**'} |")

    dense = _rows(res, "dense")
    if dense:
        L += ["", "## Dense eigensolvers (chain_damped, closed-form eigenvalues)", "",
              "Error: max over eigenvalues of |s − s_exact| / |s_exact|. η: largest backward "
              "error.",
              "`mbseig companion` is the dense general path (forced); `mbseig default` takes the "
              "structured proportional path on this family.", ""]
        methods = list(dict.fromkeys(r["method"] for r in dense))
        L += ["| n | " + " | ".join(methods) + " |", "|---|" + "---|" * len(methods)]
        for n in sorted({r["n"] for r in dense}):
            cells = []
            for m in methods:
                r = _get(dense, m, n)
                cells.append("–" if r is None else f"{_f(r['time'])} s / {_f(r['error'], '.0e')}"
                             + ("" if not math.isfinite(r.get("eta", math.nan))
                                else f" / η {r['eta']:.0e}"))
            L.append(f"| {n} | " + " | ".join(cells) + " |")
        L.append("")
        L.append("Cells: median time / eigenvalue error / backward error. Sizes above 1000 ran "
                 "once.")
        lv = res.get("left_vectors")
        if lv:
            L += ["", f"Left eigenvectors on the companion path (n = {lv['n']}): right only "
                  f"{lv['right only']:.3g} s, left and right {lv['left and right']:.3g} s "
                  f"(+{100 * (lv['left and right'] / lv['right only'] - 1):.0f} %). mbseig "
                  "computes them only when M, P or Q is not symmetric (`left=\"auto\"`): for "
                  "symmetric matrices the left vector is the conjugate of the right one, exactly, "
                  "so κ costs nothing there."]
    st = _rows(res, "structured")
    if st:
        _table(L, "Structured fast paths against eigh(Q, M) and the dense general path",
               "Floor: `scipy.linalg.eigh(Q, M)` with vectors on the same matrices, interleaved.",
               "| path | n | time | eigh(Q, M) floor | / floor | general path | speed-up | error "
               "| η |",
               st, lambda r: f"| {r['method']} | {r['n']} | {_f(r['time'])} s | "
               f"{_f(r.get('floor_time'))} s | "
               f"{_f(r.get('floor_ratio', r.get('pipeline_ratio')), '.2f')} | "
               f"{_f(r.get('general_time'))} s | {_f(r.get('speedup'), '.0f')}× | "
               f"{_f(r.get('error'), '.0e')} | {_f(r.get('eta'), '.0e')} |")
    part = _rows(res, "partial")
    if part:
        _table(L, "Partial spectrum of large sparse models (lowest 20 modes, whole pipeline)",
               "Each run in a fresh process (peak resident memory of that process). `general`: one "
               "extra dashpot makes the damping non-proportional (shift-invert Arnoldi on the "
               "companion pencil); its error column is empty (no closed form), η verifies it.",
               "| path | n | load | equilibrium | linearize | modes | total | peak RSS | error | η "
               "| runs |",
               part, lambda r: f"| {r['solver']} | {r['n']:.0e} | {r['load']:.2f} | "
               f"{r['equilibrium']:.2f} | {r['linearize']:.2f} | {r['modes']:.2f} | "
               f"{r['total']:.2f} s | {r['rss_mb']:.0f} MB | {_f(r['error'], '.0e')} | "
               f"{r['eta']:.0e} | {r['repeats']} |")
    large = _rows(res, "large")
    if large:
        L += ["", "## Large constrained model, general damping (lowest 20 modes)", "",
              "1-D chain of n masses m_i = 1 + 0.5 sin i, every 10th spring a rigid link (n/10 "
              "constraint rows in the bordered pencil), grounded dashpots on every 7th mass plus "
              "βK: non-proportional. Eigen stage only (the matrices are built directly), each "
              "solve in a fresh process, interleaved with the floor: `eigsh` shift-invert at 0 on "
              "the undamped "
              "bordered pencil (one `splu`). The optional SLEPc backend `partial-slepc` is "
              "measured against SLEPc itself in its own section below.", "",
              "| path | n | constraints | time | / floor | peak RSS | η | coverage verified "
              "| runs |",
              "|---|---|---|---|---|---|---|---|---|"]
        L.extend(f"| {r['method']} | {r['n']:.0e} | {r['m']} | {r['time']:.2f} s | "
                 f"{r['ratio']:.2f}× | {r['rss_mb']:.0f} MB | {_f(r['eta'], '.0e')} | "
                 f"{_f(r.get('verified'), '')} | "
                 f"{r['repeats']} |" for r in large)
    L += startup_lines(_rows(res, "startup"))
    sw = _rows(res, "sweeps")
    if sw:
        L += ["", "## Sweeps of the hand device", "",
              f"A 2-D sweep (k_a × c_a, {sw[0]['n']} points, continuation along each k_a line, one "
              "task per line), after a warm-up run; the four in-process rows are medians of five "
              "interleaved runs (spread: fastest and slowest run / median), the others one run "
              "each; Dask on a multi-process `LocalCluster` (a real scheduler, one thread per "
              "worker). The C4 rows sweep the tendon load f instead (the command reused); "
              "speed-ups are against the lean k_a sweep. The lean path (default) builds the case "
              "once per line and updates the swept force scalars, holding the actuator's "
              "tension when only its stiffness is swept; the general path (`lean=False`) builds "
              "and resolves every value.", "",
              "| runner | workers | time | points/s | speed-up | lean / general | spread |",
              "|---|---|---|---|---|---|---|"]
        for r in sw:
            vs = f"{r['vs_general']:.2f}×" if "vs_general" in r else ""
            spread = "{:.2f}–{:.2f}".format(*r["spread"]) if "spread" in r else ""
            L.append(f"| {r['method']} | {r['workers']} | {r['time']:.2f} s | {r['rate']:.1f} | "
                     f"{r['speedup']:.2f}× | {vs} | {spread} |")
    batch = _rows(res, "batch")
    if batch:
        r0 = batch[0]
        L += ["", "## Many points at once", "",
              "Sweeps in-process on one core (`jobs=1`, one BLAS thread): the points of a line "
              "solved together (equilibria, linear models, modes and tracking with a batch axis) "
              "where the batch can, point by point where it cannot (statics column). Time: the "
              "median of the runs after one warm-up run; spread: fastest and slowest / median. "
              f"Load average before and after: {r0.get('load', {}).get('start')} → "
              f"{r0.get('load', {}).get('end')}.", "",
              "| sweep | grid | points | time | points/s | per point | goal | met | boundaries "
              "| statics | spread | runs |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|"]
        for r in batch:
            goal = r.get("goal", "")
            if "ratio" in r:
                goal += f" (floor {r['floor_per_point'] * 1e3:.3f} ms: {r['ratio']:.1f}×)"
            elif "floor_per_point" in r:
                goal += " (EXUDYN not installed: floor not timed)"
            met = "" if "met" not in r else ("yes" if r["met"] else "**no**")
            L.append(f"| {r['method']} | {r.get('grid', '')} | {r['n']} | {r['time']:.2f} s | "
                     f"{r['rate']:.0f} | {r['per_point'] * 1e3:.3f} ms | {goal} | {met} | "
                     f"{r['boundaries']} | {', '.join(str(x) for x in r.get('statics', []))} | "
                     "{:.2f}–{:.2f}".format(*r["spread"]) + f" | {r['repeats']} |")
    if _rows(res, "uncertainty"):
        from .uncertainty_rows import report_lines

        L += report_lines(_rows(res, "uncertainty"))
    if _rows(res, "lean"):
        from .lean_rows import report_lines as lean_lines

        L += lean_lines(_rows(res, "lean"))
    small = _rows(res, "small")
    if small:
        _table(L, "Small models, stage by stage",
               "From the parsed case to the eigenvalues, in-process, one BLAS thread: medians of "
               f"{small[0]['repeats']} runs of each stage, interleaved with the eigen floor of the "
               "same run (LAPACK geev, `scipy.linalg.eig` with right vectors, of the model's 2d "
               "first companion matrix: the call a compiled peer's eigen step makes). Goal: the "
               "whole at most the peer's eigen call (EXUDYN's ≈ 0.5 ms on the spatial double "
               "pendulum, peer section).",
               "| case | DOF | build | equilibrium | linearize | modes | total | eig floor | "
               "total / floor |", small,
               lambda r: f"| {r['method']} | {r['n']} | {r['build'] * 1e3:.2f} ms | "
                         f"{r['equilibrium'] * 1e3:.2f} ms | {r['linearize'] * 1e3:.2f} ms | "
                         f"{r['modes'] * 1e3:.2f} ms ({r['solver']}) | {r['time'] * 1e3:.2f} ms | "
                         f"{r['floor'] * 1e3:.3f} ms | {r['ratio']:.0f}× |")
    if _rows(res, "peer") or res.get("peer_note"):
        L.extend(peer_lines(_rows(res, "peer"), res.get("peer_note")))
    jac = _rows(res, "jacobians")
    if jac:
        _table(L, "Jacobians of a 2-D spring network",
               "Error: max |K − K_ref| / max |K_ref| with K_ref the complex-step Jacobian (exact "
               "to rounding); for the complex step itself, its difference from the analytic K.",
               "| method | coordinates | time | error |", jac,
               lambda r: f"| {r['method']} | {r['n']} | {r['time']:.2e} s | {r['error']:.1e} |")
    rotor = _rows(res, "rotor")
    if rotor:
        _table(L, "Rotor: Campbell diagram of the overhung rotor (Friswell 5.9.x), mbseig and "
               "ROSS",
               "Time of the whole Campbell diagram (whirl, log decrements, critical speeds) and "
               "per speed, median of the stated runs; the agreement rows are the largest relative "
               "difference of the eigenvalues from ROSS at the same mesh (benchmarks/"
               "ross_friswell.py).",
               "| method | speeds | time | per speed | error | note |", rotor,
               lambda r: f"| {r['method']} | {r['n']} | {_seconds(r['time'])} | "
                         f"{_seconds(r['per_speed'])} | {_f(r['error'], '.1e')} | {r['note']} |")
    sl = _rows(res, "slepc")
    if sl:
        _table(L, "Against SLEPc: lowest 20 modes, general damping (mbseig.bench.slepc_rows)",
               "The large chain with and without its rigid links; each solve in a fresh process, "
               "interleaved, median of the stated runs (spread in brackets). `slepc`: SLEPc's PEP "
               "(TOAR, shift-and-invert at 0) on the reduced problem, its own time (the "
               "worker's imports, numpy's included, reading, assembly and the solve; not the "
               "process start and the file transfer) and its worker's peak memory; `mbseig`: "
               "`auto` with every check; `pslepc`: mbseig's partial-slepc path whole; `bslepc`: "
               "SLEPc on the bordered pencil that path hands over. Peak memory includes each "
               "interpreter's own (≈ 64 MB for mbseig's before the solve).",
               "| model | n | kind | time | peak memory | / reference | runs |", sl,
               lambda r: f"| {r['model']} | {r['n']:.0e} | {r['method']} | "
                         f"{r['time']:.2f} s ({r['spread'][0]:.2f}–{r['spread'][1]:.2f}) | "
                         f"{r['rss_mb']:.0f} MB | "
                         + (f"{r['ratio']:.2f}× time, {r['mem_ratio']:.2f}× memory"
                            if "ratio" in r else "–") + f" | {r['repeats']} |")
    spatial = _rows(res, "spatial")
    if spatial:
        _table(L, "A large spatial model: read and assemble",
               "A chain of spatial rigid bodies on 6×6 bushings (mbseig.bench.spatial_rows; "
               "benchmarks/spatial_chain.py runs it through the whole pipeline), medians of the "
               "stated runs; floor: tomllib alone on the case text and M, Φ_q as CSR from their "
               "own triplets.",
               "| model | coordinates | read + assemble | first Φ, Φ_q, g, K, C | floor | runs |",
               spatial, _spatial_line)
    beams = _rows(res, "beams")
    if beams:
        _table(L, "3-D beams: a large beam model (10⁵ DOF in the full run), lowest 20 modes",
               "A comb of oblique Euler–Bernoulli cantilevers of 1 + 0.1 k m "
               "(mbseig.bench.beam_rows; benchmarks/beam3d_large.py runs other sizes): read and "
               "build, equilibrium, sparse linearization and the lowest 20 modes, median wall time "
               "of the stated runs; error: the largest relative difference of the 20 frequencies "
               "from the closed forms (Blevins table 8-1), set by the conditioning of the bars' "
               "lowest eigenvalues at this mesh, not by the mesh (docs/beams3d.md). ROSS builds "
               "rotors along one axis and cannot build this model.",
               "| model | DOF | path | load | equilibrium | linearize | modes | total | error | "
               "runs |", beams,
               lambda r: f"| {r['beams']} × {r['elements']} elements | {r['n']} | {r['solver']} | "
                         + " | ".join(_seconds(r['stages'][k]) for k in
                                      ("load", "equilibrium", "linearize", "modes"))
                         + f" | {_seconds(r['time'])} | {r['error']:.1e} | {r['repeats']} |")
    cs = _rows(res, "constraint")
    if cs:
        L += ["", "## Linearization with and without the constraint-force stiffness", "",
              "| case and linearization | ω₁ [rad/s] | relative error | time | reference |",
              "|---|---|---|---|---|"]
        for r in cs:
            L.append(f"| {r['method']} | {r['omega']:.6g} | {r['error']:.1e} | {r['time']:.2e} s | "
                     f"{r['reference']} |")
    td = _rows(res, "timedomain")
    L += ["", "## Time-domain check: integrator settings (Ziegler pendulum past the flutter load)",
          ""]
    if td:
        L += ["| integrator | mode | δ predicted | δ measured | rel. error | check | time |",
              "|---|---|---|---|---|---|---|"]
        for r in td:
            L.append(f"| {r['method']} | {r['n']} | {r['predicted_delta']:+.5g} | "
                     f"{r['measured_delta']:+.5g} | {r['error']:.1e} | "
                     f"{'pass' if r['passed'] else 'FAIL'} | {r['time']:.2f} s |")
        L.append("")
        L.append("The default (DOP853 at rtol 1e-10) adds no measurable damping. Implicit methods "
                 "at a loose tolerance damp the response numerically: the measured δ moves towards "
                 "the stable side, which on a marginal mode can turn growth into apparent decay; "
                 "the check's 1 % tolerance catches it.")
    else:
        L.append(res.get("timedomain_note") or "not run")
    L.extend(_nlevp_lines(_rows(res, "nlevp")))
    fails = res.get("failures")
    if fails:
        _table(L, "Stability where methods fail",
               "Each row: the naive method, its answer, mbseig's answer, and the reference that "
               "decides (asserted in tests/test_failures.py).",
               "| case | naive method | naive answer | mbseig | reference | naive wrong "
               "| mbseig right |",
               fails, lambda c: f"| {c['name']} | {c['naive_method']} | {c['naive']} | "
               f"{c['mbseig']} | {c['reference']} | {'yes' if c['naive_wrong'] else 'no'} | "
               f"{'yes' if c['mbseig_right'] else '**no**'} |")
    (out_dir / "benchmarks.md").write_text("\n".join(L) + "\n")
    plots.save(plots.speed_accuracy(res), out_dir / "speed_accuracy.png", dpi=120)
