"""Per-sample cost of the estimator (issue 5): C++, Python binding, numpy reference, RLS baseline.

Run from the repository root::

    python bench/per_sample.py            # every figure from 1 round of timing
    python bench/per_sample.py --rounds 3 # the full run: 3 rounds, each figure's best median kept
    python bench/per_sample.py --quick    # fewer windows, no callgrind, no x86-64-v3 build
    python bench/per_sample.py --baseline b531827   # and the code of that revision, side by side

What it does, in one process so every ratio compares figures from the same run:

1. builds ``bench/cpp`` with CMake in Release (``-O3 -DNDEBUG``, no ``-march``: the flags of the
   wheel's baseline build ``algid._core``) and, separately, with ``-march=x86-64-v3`` and
   ``-march=x86-64-v4`` plus ``-ffp-contract=off`` (the flags of ``algid._core_v3`` and
   ``_core_v4``, reported as ``*_v3`` / ``*_v4``) where this CPU runs them;
2. runs ``bench_per_sample`` (steady_clock; median / p99 of 16-sample batches, worst single
   sample, per DOF-sample) for ChainEstimator ``update()`` ("default"), the run-time sized
   ChainEstimator<Dynamic> at the same n ("dynamic"), the batch path ``record()`` ("batch", what
   the Python ``run()`` calls), the continuous configuration and an RLS baseline at n = 1, 3,
   10, 50 in double and float; with ``--baseline REF`` also the same bench built from git
   revision REF, in every round ("baseline_*", and the after / before ratios);
3. counts instructions per DOF-sample under ``valgrind --tool=callgrind`` (client requests
   bracket the measured loop);
4. times the Python per-sample ``update()``, the batch ``run()`` of the fixed-size and of the
   run-time sized class (GIL released; for every instruction-set build the CPU runs, the
   default one first) and the numpy reference
   ``algid.estimator.reference.estimate`` on the same kind of signals;
5. counts the flops per DOF-sample on an instrumented scalar type (``flop_count``) and measures
   the machine's multiply-add peak (``peak_flops``), giving a lower bound;
6. measures single-precision accuracy on Table 1 (``float_accuracy``);
7. writes ``bench/results/per_sample.json`` and prints a table.

Timings are never asserted; the "targets" block records whether this run met issue 5's figures.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import datetime as _dt
import functools
import json
import os
import platform
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "bench" / "results" / "per_sample.json"
SIZES = (1, 3, 10, 50)
DT = 1e-3  # [s]


# ---------------------------------------------------------------------------------------------
# building and running the C++ side


def cmake_build(build_dir: Path, targets: list[str], extra_flags: str = "", source: Path = ROOT) -> Path:
    """Configure (Release, optional extra CXX flags) and build the given bench targets."""
    gen = ["-G", "Ninja"] if shutil.which("ninja") else []
    cfg = [
        "cmake",
        "-S",
        str(source),
        "-B",
        str(build_dir),
        *gen,
        "-DCMAKE_BUILD_TYPE=Release",
        "-DALGID_BUILD_BENCH=ON",
        "-DALGID_BUILD_TESTS=OFF",
        "-DALGID_BUILD_PYTHON=OFF",
        f"-DCMAKE_CXX_FLAGS={extra_flags}",
    ]
    subprocess.run(cfg, check=True, stdout=subprocess.DEVNULL)
    # -j2: the machine has 2 cores, shared; one build at a time.
    subprocess.run(
        ["cmake", "--build", str(build_dir), "-j2", "--target", *targets], check=True, stdout=subprocess.DEVNULL
    )
    return build_dir / "bench" / "cpp"


def baseline_source(ref: str, build_dir: Path) -> Path:
    """A checkout of git revision `ref` (a detached worktree under `build_dir`): the code the
    current figures are compared with, built and timed in the same run."""
    path = build_dir / "baseline-src"
    if path.exists():
        subprocess.run(
            ["git", "-C", str(ROOT), "worktree", "remove", "--force", str(path)],
            check=False,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        shutil.rmtree(path, ignore_errors=True)
    subprocess.run(
        ["git", "-C", str(ROOT), "worktree", "add", "--detach", str(path), ref],
        check=True,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    return path


def json_lines(cmd: list[str]) -> list[dict]:
    out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    return [json.loads(line) for line in out.splitlines() if line.startswith("{")]


def callgrind_instructions(binary: Path, subject: str, n: int, scalar: str) -> float | None:
    """Instructions per DOF-sample of `updates` update() calls between client requests."""
    updates = max(100, 3000 // n) if subject != "continuous" else max(600, 3000 // n)  # >= 8 harvests
    with tempfile.TemporaryDirectory() as tmp:
        out_file = Path(tmp) / "callgrind.out"
        cmd = [
            "valgrind",
            "--tool=callgrind",
            "--instr-atstart=no",
            f"--callgrind-out-file={out_file}",
            str(binary),
            "--callgrind",
            subject,
            str(n),
            scalar,
            str(updates),
        ]
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode != 0 or not out_file.exists():
            return None
        info = json.loads(next(line for line in proc.stdout.splitlines() if line.startswith("{")))
        if not info.get("callgrind_client_requests"):
            return None  # no valgrind/callgrind.h at build time: the count would include setup
        text = out_file.read_text()
        m = re.search(r"^totals:\s+(\d+)", text, re.M) or re.search(r"^summary:\s+(\d+)", text, re.M)
        return int(m.group(1)) / (updates * n) if m else None


# ---------------------------------------------------------------------------------------------
# Python side


def load_signals(binary: Path, n: int, samples: int) -> tuple[np.ndarray, np.ndarray]:
    """The C++ bench's own signals (closed-form multisine chain, Table 1 for n = 3), so that
    Python and C++ are timed on the same numbers. Accelerations [m/s^2], forces [N], (T, n)."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "signals.bin"
        subprocess.run([str(binary), "--dump", str(n), str(samples), str(path)], check=True)
        raw = np.fromfile(path, dtype=np.float64)
    a, u = raw.reshape(2, samples, n)
    return np.ascontiguousarray(a), np.ascontiguousarray(u)


def config() -> object:
    """The estimators' configuration at the bench's sample period (C++ defaults otherwise)."""
    import algid

    cfg = algid.ChainConfig()
    cfg.dt = DT
    return cfg


def python_figures(a: np.ndarray, u: np.ndarray, reps: int, isa: str | None = None) -> dict:
    """Python update() (default build only) and run() of the chain estimators of build `isa`:
    the fixed-size class of n ("python_run") and the run-time sized one ("python_run_dynamic"),
    timed alternately."""
    import algid
    from algid.estimator import chain_core

    samples, n = a.shape
    out: dict[str, dict] = {}
    core = chain_core(isa)
    makers = {"python_run": getattr(core, f"ChainEstimator{n}"), "python_run_dynamic": core.ChainEstimatorDynamic}

    if isa is None:
        # Per-sample update(): each call timed (minus the timer's own median cost).
        est = algid.ChainEstimator(n, DT)
        clock = statistics.median(-(time.perf_counter_ns() - time.perf_counter_ns()) for _ in range(2000))
        per_call = []
        for rep in range(reps + 1):
            est.reset()
            for j in range(samples):
                t0 = time.perf_counter_ns()
                est.update(a[j], u[j])
                t1 = time.perf_counter_ns()
                if rep and j >= 16:
                    per_call.append(max(0.0, t1 - t0 - clock))
        per_call = np.asarray(per_call) / n
        out["python_update"] = {
            "ns_per_dof_sample_median": float(np.median(per_call)),
            "p99": float(np.percentile(per_call, 99)),
            "max": float(per_call.max()),
            "samples": samples,
            "reps": reps,
            "isa": algid.ISA,
        }

    # Batch run(): GIL released; includes filling the (T, n) output arrays. Whole record per call,
    # the same protocol as the C++ window_min figure (whole window / T, min over windows): on a
    # shared machine the min is the figure least disturbed by other jobs.
    per_rep: dict[str, list[float]] = {key: [] for key in makers}
    for rep in range(2 * reps + 1):
        for key, make in makers.items():
            est = make(config(), n)
            t0 = time.perf_counter_ns()
            est.run(a, u, False)
            t1 = time.perf_counter_ns()
            if rep:
                per_rep[key].append((t1 - t0) / (samples * n))
    for key, times in per_rep.items():
        out[key] = {
            "ns_per_dof_sample_median": float(np.median(times)),
            "window_min": float(min(times)),
            "p99": None,
            "max": None,
            "samples": samples,
            "reps": len(times),
            "isa": isa or algid.ISA,
            "note": "one timing per whole-record call (T samples); median and min over calls",
        }
    return out


@contextlib.contextmanager
def cached_quadrature_weights(enabled: bool = True):
    """The numpy reference with its quadrature weights computed once per process: the timed
    calls then exclude their computation (the reference memoises them itself too, so only the
    first call of a process differs)."""
    from algid.estimator import reference

    original = reference.quadrature_weights
    if enabled:
        reference.quadrature_weights = functools.lru_cache(maxsize=None)(original)
    try:
        yield reference
    finally:
        reference.quadrature_weights = original


def numpy_reference_figures(
    a_all: np.ndarray, u_all: np.ndarray, samples: tuple[int, int], cached_weights: bool, reps: int = 3
) -> dict:
    """Whole-record numpy reference: total per DOF-sample at both lengths, and the marginal cost
    (difference of the two, which removes fixed per-call costs); min over `reps` calls."""
    n = a_all.shape[1]
    times = {}
    with cached_quadrature_weights(cached_weights) as reference:
        for T in samples:
            a, u = a_all[:T], u_all[:T]
            best = None
            for _ in range(reps):  # min over repetitions: robust to other load on the machine
                t0 = time.perf_counter_ns()
                reference.estimate(a, u, DT)
                dt_ns = time.perf_counter_ns() - t0
                best = dt_ns if best is None else min(best, dt_ns)
            times[T] = best
    t_short, t_long = samples
    return {
        "ns_per_dof_sample_median": times[t_long] / (t_long * n),
        "ns_per_dof_sample_at": {str(T): times[T] / (T * n) for T in samples},
        "marginal_ns_per_dof_sample": (times[t_long] - times[t_short]) / ((t_long - t_short) * n),
        "p99": None,
        "max": None,
        "cached_weights": cached_weights,
    }


def interleaved_numpy_ratio(a_all: np.ndarray, u_all: np.ndarray, reps: int, run_samples: int = 2000) -> dict:
    """numpy reference / Python run() measured back to back, `reps` times: each repetition times
    the reference (cached weights) on 1000 and 4000 samples (marginal cost per DOF-sample, which
    removes its fixed per-call costs) and then Python run() (default build) on `run_samples`
    samples (min of 5 calls). Both sides of each ratio see the same state of the shared machine,
    whose speed moves by tens of percent between minutes: the per-repetition ratios are the
    robust figure, the separate minima are not."""
    import algid
    from algid.estimator import chain_core

    n = a_all.shape[1]
    make = getattr(chain_core(), f"ChainEstimator{n}")
    marginal, run, ratio = [], [], []
    with cached_quadrature_weights() as reference:
        reference.estimate(a_all[:1000], u_all[:1000], DT)  # warm the weights cache
        for _ in range(reps):
            t0 = time.perf_counter_ns()
            reference.estimate(a_all[:1000], u_all[:1000], DT)
            t1 = time.perf_counter_ns()
            reference.estimate(a_all[:4000], u_all[:4000], DT)
            t2 = time.perf_counter_ns()
            best = None
            for _ in range(5):
                est = make(config(), n)
                t3 = time.perf_counter_ns()
                est.run(a_all[:run_samples], u_all[:run_samples], False)
                dt_ns = time.perf_counter_ns() - t3
                best = dt_ns if best is None else min(best, dt_ns)
            marginal.append(((t2 - t1) - (t1 - t0)) / (3000 * n))
            run.append(best / (run_samples * n))
            ratio.append(marginal[-1] / run[-1])
    return {
        "isa": algid.ISA,
        "reps": reps,
        "numpy_marginal_ns_per_dof_sample": marginal,
        "python_run_ns_per_dof_sample": run,
        "ratio_per_rep": ratio,
        "ratio_median": float(statistics.median(ratio)),
        "ratio_min": float(min(ratio)),
        "ratio_of_minima": float(min(marginal) / min(run)),
    }


# ---------------------------------------------------------------------------------------------


def machine_info() -> dict:
    info = {"platform": platform.platform(), "python": platform.python_version(), "nproc": os.cpu_count()}
    try:
        lscpu = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        for key in ("Model name", "CPU max MHz", "L1d cache", "L2 cache"):
            m = re.search(rf"^{key}:\s+(.*)$", lscpu, re.M)
            if m:
                info[key.lower().replace(" ", "_")] = m.group(1).strip()
        info["avx512f"] = " avx512f" in lscpu
    except OSError:
        pass
    try:
        info["compiler"] = subprocess.run(["c++", "--version"], capture_output=True, text=True).stdout.splitlines()[0]
    except (OSError, IndexError):
        pass
    try:
        info["commit"] = subprocess.run(
            ["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True, text=True
        ).stdout.strip()
    except OSError:
        pass
    return info


@dataclasses.dataclass
class Builds:
    """The bench binaries' directories: the default build, the wider ones the wheel also ships
    (algid._core_v3, _core_v4) where the compiler and this CPU run them ({"v3": dir, ...}), and
    the baseline revision's, built with the same flags ({"": dir, "_v3": dir, ...})."""

    bindir: Path
    wide_dirs: dict[str, Path]
    baseline_dirs: dict[str, Path]


@dataclasses.dataclass
class Measurements:
    """Everything the run measured, before any figure is derived from it."""

    configs: dict[str, dict[str, dict]]
    other_isas: list[str]
    interleaved: dict[str, dict]
    flops: list[dict]
    peak_default: list[dict]
    peak_wide: dict[str, list[dict]]
    accuracy: list[dict]
    load_before: tuple[float, float, float]
    load_after: tuple[float, float, float]
    continuous_note: str


@dataclasses.dataclass
class Derived:
    """The figures computed from the measurements (flops, peak, bounds, ratios)."""

    flops_per_dof: dict[int, dict]
    rls_flops: float | None
    peak: dict[str, dict]
    bound: dict[str, dict]
    run_cpp: str
    rls_ratio: dict[str, float]
    rls_ratio_instructions: dict[str, float]
    runtime_over_fixed: dict[str, dict]
    after_over_before: dict[str, dict]


def figure(configs: dict, config: str, n: int) -> dict:
    """The figures of `config` at `n`, {} where that configuration or size was not measured."""
    return configs.get(config, {}).get(str(n), {})


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--build-dir", type=Path, default=ROOT / "build" / "bench")
    ap.add_argument("--quick", action="store_true", help="3 windows, no callgrind, no x86-64-v3/v4 builds")
    ap.add_argument("--no-wide", action="store_true", help="skip the -march=x86-64-v3 and -v4 builds")
    ap.add_argument("--no-callgrind", action="store_true")
    ap.add_argument(
        "--rounds", type=int, default=1, help="repetitions of the timing, best median kept (default: 1; full run: 3)"
    )
    ap.add_argument("--output", type=Path, default=RESULTS)
    ap.add_argument(
        "--baseline",
        metavar="REF",
        help="also build bench/cpp at git revision REF and time it in "
        "every round (configurations baseline_*): before/after figures from one run",
    )
    args = ap.parse_args(argv)
    if args.quick:
        args.rounds = 1
    return args


def build_wide(args: argparse.Namespace) -> dict[str, Path]:
    """The -march=x86-64-v3 / -v4 builds this CPU runs (none with --quick or --no-wide)."""
    wide_dirs: dict[str, Path] = {}
    if args.quick or args.no_wide:
        return wide_dirs
    import algid._core as core

    for level in ("v3", "v4"):
        if not core.cpu_supports(f"x86-64-{level}"):
            continue
        print(
            f"building bench/cpp (Release, -O3 -march=x86-64-{level} -ffp-contract=off: algid._core_{level}'s "
            "flags) ...",
            flush=True,
        )
        wide_dirs[level] = cmake_build(
            args.build_dir / f"x86-64-{level}",
            ["bench_per_sample", "peak_flops"],
            f"-march=x86-64-{level} -ffp-contract=off",
        )
    return wide_dirs


def build_baseline(args: argparse.Namespace, wide_dirs: dict[str, Path]) -> dict[str, Path]:
    """The --baseline revision's bench, with the default flags and those of every wide build."""
    baseline_dirs: dict[str, Path] = {}
    if not args.baseline:
        return baseline_dirs
    source = baseline_source(args.baseline, args.build_dir)
    print(f"building bench/cpp of {args.baseline} (the baseline) ...", flush=True)
    baseline_dirs[""] = cmake_build(args.build_dir / "baseline-default", ["bench_per_sample"], source=source)
    for level in wide_dirs:
        baseline_dirs[f"_{level}"] = cmake_build(
            args.build_dir / f"baseline-x86-64-{level}",
            ["bench_per_sample"],
            f"-march=x86-64-{level} -ffp-contract=off",
            source=source,
        )
    return baseline_dirs


def build_benches(args: argparse.Namespace) -> Builds:
    targets = ["bench_per_sample", "flop_count", "peak_flops", "float_accuracy"]
    print("building bench/cpp (Release, -O3, no -march) ...", flush=True)
    bindir = cmake_build(args.build_dir / "default", targets)
    wide_dirs = build_wide(args)
    return Builds(bindir, wide_dirs, build_baseline(args, wide_dirs))


def other_python_isas() -> list[str]:
    """The instruction-set builds of algid the CPU runs besides the default one
    (reported as python_run_double_<isa>)."""
    import algid
    from algid.estimator import chain_core

    other_isas = []
    for isa in ("x86-64", "x86-64-v3", "x86-64-v4"):
        try:
            if isa != algid.ISA and chain_core(isa):
                other_isas.append(isa)
        except (RuntimeError, ValueError):
            pass
    return other_isas


def time_cpp_round(builds: Builds, windows: int, add) -> None:
    """One round of every C++ bench binary (default, wide, baseline), rows passed to `add`."""
    binaries = [("", builds.bindir, "")]
    binaries += [("", wide_dir, f"_{level}") for level, wide_dir in builds.wide_dirs.items()]
    binaries += [("baseline_", base_dir, suffix) for suffix, base_dir in builds.baseline_dirs.items()]
    for prefix, bench_dir, suffix in binaries:
        for row in json_lines([str(bench_dir / "bench_per_sample"), "--windows", str(windows)]):
            add(
                f"{prefix}{row['config']}_{row['scalar']}{suffix}",
                row["n"],
                {k: v for k, v in row.items() if k not in ("config", "n", "scalar")},
            )


def time_rounds(
    args: argparse.Namespace, builds: Builds, signals: dict, other_isas: list[str]
) -> dict[tuple[str, int], list[dict]]:
    """C++ and Python timed back to back, `args.rounds` times: {(config, n): [figures per round]}."""
    windows = 3 if args.quick else 5
    py_reps = 2 if args.quick else 3
    rounds: dict[tuple[str, int], list[dict]] = {}

    def add(config: str, n: int, figures: dict) -> None:
        rounds.setdefault((config, n), []).append(figures)

    for r in range(args.rounds):
        print(f"round {r + 1}/{args.rounds}: C++ (steady_clock), Python update()/run() ...", flush=True)
        time_cpp_round(builds, windows, add)
        for n in SIZES:
            a, u = signals[n]
            for key, f in python_figures(a[:2000], u[:2000], py_reps).items():
                add(f"{key}_double", n, f)
            for isa in other_isas:
                for key, f in python_figures(a[:2000], u[:2000], py_reps, isa).items():
                    add(f"{key}_double_{isa}", n, f)
    return rounds


def best_of_rounds(rounds: dict[tuple[str, int], list[dict]]) -> dict[str, dict[str, dict]]:
    """The machine is shared (other jobs come and go, and its speed moves by tens of percent
    between rounds), so each figure keeps the round with the lowest median, p99 from that round,
    max = the worst over all rounds, max_path = the best over all rounds; `round_medians` shows
    the spread. Returns {config: {str(n): figures}}."""
    configs: dict[str, dict[str, dict]] = {}
    for (config, n), rows in rounds.items():
        best = dict(min(rows, key=lambda f: f["ns_per_dof_sample_median"]))
        best["round_medians"] = [f["ns_per_dof_sample_median"] for f in rows]
        if all(f.get("window_min") is not None for f in rows):
            best["window_min"] = min(f["window_min"] for f in rows)
        if all(f.get("max") is not None for f in rows):
            best["max"] = max(f["max"] for f in rows)
        if all(f.get("max_path") is not None for f in rows):
            best["max_path"] = min(f["max_path"] for f in rows)
        configs.setdefault(config, {})[str(n)] = best
    return configs


def count_instructions(args: argparse.Namespace, builds: Builds, configs: dict) -> None:
    """Fill in instructions_per_dof_sample (None where callgrind did not run)."""
    for by_n in configs.values():
        for fig in by_n.values():
            fig["instructions_per_dof_sample"] = None
    if shutil.which("valgrind") is None or args.quick or args.no_callgrind:
        return
    print("counting instructions (callgrind) ...", flush=True)
    for subject in [c for c in ("default", "batch", "continuous", "rls") if f"{c}_double" in configs]:
        for scalar in ("double", "float"):
            for n in SIZES:
                ipds = callgrind_instructions(builds.bindir / "bench_per_sample", subject, n, scalar)
                configs[f"{subject}_{scalar}"][str(n)]["instructions_per_dof_sample"] = ipds
    if "v3" in builds.wide_dirs:  # valgrind 3.19 runs AVX2 code, not AVX-512
        for subject in ("default", "batch"):
            for n in SIZES:
                ipds = callgrind_instructions(builds.wide_dirs["v3"] / "bench_per_sample", subject, n, "double")
                configs[f"{subject}_double_v3"][str(n)]["instructions_per_dof_sample"] = ipds


def continuous_note(configs: dict) -> str:
    if "continuous_double" in configs:
        return (
            "ContinuousEstimator<N, Scalar> with its default configuration (K = 4 staggered 0.5 s "
            "weak-form windows, joint estimate, change detection on), one uninterrupted signal"
        )
    return (
        "algid::ContinuousEstimator is not in the core (cpp/include/algid/continuous_estimator.hpp "
        "missing at build time): not measured"
    )


def time_numpy_reference(args: argparse.Namespace, configs: dict, signals: dict) -> dict[str, dict]:
    """The numpy reference's configurations (added to `configs`); returns the interleaved ratios."""
    print("timing the numpy reference ...", flush=True)
    for n in SIZES:
        configs.setdefault("numpy_reference_cached_weights_double", {})[str(n)] = numpy_reference_figures(
            *signals[n], (1000, 4000), cached_weights=True, reps=2 if args.quick else 6
        )
    print("numpy reference and Python run() back to back ...", flush=True)
    interleaved = {str(n): interleaved_numpy_ratio(*signals[n], reps=3 if args.quick else 8) for n in SIZES}
    # As shipped (reference.quadrature_weights recomputed per signal: a fixed ~0.25 s x 6n).
    configs.setdefault("numpy_reference_double", {})["3"] = numpy_reference_figures(
        *signals[3], (1000, 4000), cached_weights=False, reps=1
    )
    return interleaved


def measure(args: argparse.Namespace, builds: Builds, load_before: tuple) -> Measurements:
    """Every timing, count and accuracy figure of the run (`load_before`: before the builds)."""
    other_isas = other_python_isas()
    signals = {n: load_signals(builds.bindir / "bench_per_sample", n, 4000) for n in SIZES}
    configs = best_of_rounds(time_rounds(args, builds, signals, other_isas))
    count_instructions(args, builds, configs)
    interleaved = time_numpy_reference(args, configs, signals)
    print("counting flops, measuring peak and float accuracy ...", flush=True)
    flops = json_lines([str(builds.bindir / "flop_count")])
    peak_default = json_lines([str(builds.bindir / "peak_flops")])
    peak_wide = {level: json_lines([str(d / "peak_flops")]) for level, d in builds.wide_dirs.items()}
    accuracy = json_lines([str(builds.bindir / "float_accuracy")])
    return Measurements(
        configs=configs,
        other_isas=other_isas,
        interleaved=interleaved,
        flops=flops,
        peak_default=peak_default,
        peak_wide=peak_wide,
        accuracy=accuracy,
        load_before=load_before,
        load_after=os.getloadavg(),
        continuous_note=continuous_note(configs),
    )


def peak_figures(rows: list[dict]) -> dict:
    """A build's multiply-add peak: best over lane widths, scalar (1 lane), float."""

    def best_peak(scalar: str) -> float | None:
        vals = [r["gflops"] for r in rows if r.get("scalar") == scalar]
        return max(vals) if vals else None

    def scalar_peak(scalar: str) -> float | None:
        vals = [r["gflops"] for r in rows if r.get("scalar") == scalar and r.get("lanes") == 1]
        return vals[0] if vals else None

    return {
        "isa": next((r["isa"] for r in rows if "isa" in r), None),
        "double_gflops": best_peak("double"),
        "double_scalar_gflops": scalar_peak("double"),
        "float_gflops": best_peak("float"),
        "rows": [r for r in rows if "lanes" in r],
    }


def lower_bound(m: Measurements, flops_per_dof: dict, peak: dict, wide_levels: list[str]) -> dict[str, dict]:
    """Counted flops over each build's peak, per n. The lane layout (n >= 3) computes whole
    registers: lane_slots lanes for n DOF, the padding lanes included (n = 3 in 4 lanes: 4/3 of
    the useful flops). Counted flops are the useful ones; the bound of a build uses what that
    build executes."""
    fig = functools.partial(figure, m.configs)
    build_config = {
        "default_flags": "default_double",
        "x86-64-v3": "default_double_v3",
        "x86-64-v4": "default_double_v4",
    }
    bound = {}
    for n in SIZES:
        f = flops_per_dof.get(n, {}).get("flops_per_dof_sample")
        measured = fig("default_double", n).get("ns_per_dof_sample_median")
        entry = {"flops_per_dof_sample": f, "measured_ns": measured}
        for name, p in peak.items():
            slots = fig(build_config.get(name, ""), n).get("lane_slots") or n
            executed = f * slots / n if f else None
            entry[f"lane_slots_{name}"] = slots
            for kind in ("double_gflops", "double_scalar_gflops"):
                if executed and p.get(kind):
                    entry[f"bound_ns_{name}_{kind.replace('_gflops', '')}"] = executed / p[kind]
        if f and measured:
            entry["achieved_gflops"] = f / measured
        for level in wide_levels:
            batch_wide = fig(f"batch_double_{level}", n).get("ns_per_dof_sample_median")
            if f and batch_wide:
                entry[f"measured_ns_batch_{level}"] = batch_wide
                entry[f"achieved_gflops_batch_{level}"] = f / batch_wide
        bound[str(n)] = entry
    return bound


def runtime_over_fixed_ratios(m: Measurements, wide_levels: list[str]) -> dict[str, dict]:
    """The run-time sized estimator against the fixed-size one at the same n, same build and run."""
    fig = functools.partial(figure, m.configs)
    runtime_over_fixed = {}
    for suffix in ["", *(f"_{level}" for level in wide_levels)]:
        for scalar in ("double", "float"):
            ratios = {
                str(n): fig(f"dynamic_{scalar}{suffix}", n)["ns_per_dof_sample_median"]
                / fig(f"default_{scalar}{suffix}", n)["ns_per_dof_sample_median"]
                for n in SIZES
                if fig(f"dynamic_{scalar}{suffix}", n) and fig(f"default_{scalar}{suffix}", n)
            }
            if ratios:
                runtime_over_fixed[f"update_{scalar}{suffix}"] = ratios
    for isa in [None, *m.other_isas]:
        suffix = f"_{isa}" if isa else ""
        runtime_over_fixed[f"python_run{suffix}"] = {
            str(n): fig(f"python_run_dynamic_double{suffix}", n)["window_min"]
            / fig(f"python_run_double{suffix}", n)["window_min"]
            for n in SIZES
            if fig(f"python_run_dynamic_double{suffix}", n)
        }
    return runtime_over_fixed


def after_over_before_ratios(configs: dict) -> dict[str, dict]:
    """After over before, where a baseline was timed: < 1 is faster now."""
    fig = functools.partial(figure, configs)
    after_over_before = {}
    for config in sorted(configs):
        if config.startswith("baseline_") and config[len("baseline_") :] in configs:
            now = config[len("baseline_") :]
            after_over_before[now] = {
                str(n): fig(now, n)["ns_per_dof_sample_median"] / fig(config, n)["ns_per_dof_sample_median"]
                for n in SIZES
                if fig(now, n) and fig(config, n)
            }
    return after_over_before


def derive(m: Measurements, builds: Builds) -> Derived:
    import algid

    fig = functools.partial(figure, m.configs)
    wide_levels = list(builds.wide_dirs)
    flops_per_dof = {r["n"]: r for r in m.flops if r["subject"] == "default"}
    peak = {"default_flags": peak_figures(m.peak_default)}
    for level, rows in m.peak_wide.items():
        peak[f"x86-64-{level}"] = peak_figures(rows)
    run_cpp = {"x86-64-v3": "batch_double_v3", "x86-64-v4": "batch_double_v4"}.get(algid.ISA, "default_double")
    return Derived(
        flops_per_dof=flops_per_dof,
        rls_flops=next((r["flops_per_dof_sample"] for r in m.flops if r["subject"] == "rls"), None),
        peak=peak,
        bound=lower_bound(m, flops_per_dof, peak, wide_levels),
        run_cpp=run_cpp if fig(run_cpp, 3) else "default_double",
        rls_ratio={
            str(n): fig("default_double", n)["ns_per_dof_sample_median"]
            / fig("rls_double", n)["ns_per_dof_sample_median"]
            for n in SIZES
        },
        rls_ratio_instructions={
            str(n): fig("default_double", n)["instructions_per_dof_sample"]
            / fig("rls_double", n)["instructions_per_dof_sample"]
            for n in SIZES
            if fig("default_double", n).get("instructions_per_dof_sample")
            and fig("rls_double", n).get("instructions_per_dof_sample")
        },
        runtime_over_fixed=runtime_over_fixed_ratios(m, wide_levels),
        after_over_before=after_over_before_ratios(m.configs),
    )


def python_run_targets(m: Measurements, d: Derived) -> dict[str, dict]:
    """Python run() against the C++ loop it wraps, same build: ChainEstimator::record() blocks in
    the wider builds (blocks for n = 1, the lane layout for n >= 3), update() sample by sample in
    the baseline build."""
    import algid

    fig = functools.partial(figure, m.configs)
    return {
        str(n): {
            "isa": algid.ISA,
            "cpp_config": d.run_cpp,
            "ratio": fig("python_run_double", n)["window_min"] / fig(d.run_cpp, n)["window_min"],
            "ratio_to_cpp_default_update_median": fig("python_run_double", n)["window_min"]
            / fig("default_double", n)["ns_per_dof_sample_median"],
            "met": fig("python_run_double", n)["window_min"] <= 1.5 * fig(d.run_cpp, n)["window_min"],
        }
        for n in SIZES
        if fig(d.run_cpp, n)
    }


def numpy_targets(m: Measurements) -> dict[str, dict]:
    """The numpy reference over Python run(), per n."""
    import algid

    fig = functools.partial(figure, m.configs)
    targets = {}
    for n in SIZES:
        run = fig("python_run_double", n)["window_min"]
        cached = fig("numpy_reference_cached_weights_double", n)
        entry = {
            "isa": algid.ISA,
            # the figure: numpy reference and run() timed back to back, median over repetitions
            "ratio_interleaved_median": m.interleaved[str(n)]["ratio_median"],
            "ratio_interleaved_min": m.interleaved[str(n)]["ratio_min"],
            # the same from the separate measurements (numpy timed after every round)
            "ratio_marginal_cached": cached["marginal_ns_per_dof_sample"] / run,
            "ratio_whole_call_cached": cached["ns_per_dof_sample_median"] / run,
        }
        if fig("python_run_double_x86-64", n):
            entry["ratio_marginal_cached_x86-64_build"] = (
                cached["marginal_ns_per_dof_sample"] / fig("python_run_double_x86-64", n)["window_min"]
            )
        targets[str(n)] = entry
    as_shipped = fig("numpy_reference_double", 3)
    run3 = fig("python_run_double", 3)
    if as_shipped and run3:
        targets["3"]["ratio_whole_call_as_shipped"] = as_shipped["ns_per_dof_sample_median"] / run3["window_min"]
    for t in targets.values():
        t["met"] = t["ratio_interleaved_median"] >= 50
    return targets


def max_targets(configs: dict) -> dict[str, dict]:
    """The worst single update() (raw, and its data-dependent path) over the median, per n."""
    fig = functools.partial(figure, configs)
    targets = {}
    for n in SIZES:
        median = fig("default_double", n)["ns_per_dof_sample_median"]
        t = {
            "max_over_median": fig("default_double", n)["max"] / median,
            "max_path_over_median": fig("default_double", n)["max_path"] / median,
        }
        t["met_raw_max"] = t["max_over_median"] <= 5
        t["met_path_max"] = t["max_path_over_median"] <= 5
        targets[str(n)] = t
    return targets


def issue5_targets(m: Measurements, d: Derived) -> dict[str, dict]:
    """Whether this run met issue 5's figures (recorded, never asserted)."""
    fig = functools.partial(figure, m.configs)
    n3 = fig("default_double", 3).get("ns_per_dof_sample_median")
    n50 = fig("default_double", 50).get("ns_per_dof_sample_median")
    float_1k = [r for r in m.accuracy if r["scalar"] == "float" and r["rate_hz"] == 1000]
    return {
        "median_ns_per_dof_sample_n3_le_100": {"value": n3, "limit": 100, "met": (n3 or 1e9) <= 100},
        "linear_in_n_n50_per_dof_le_n3": {"n50": n50, "n3": n3, "met": (n50 or 1e9) <= (n3 or 0)},
        "python_run_within_1.5x_of_cpp": python_run_targets(m, d),
        "python_run_at_least_50x_faster_than_numpy_reference": numpy_targets(m),
        "max_within_5x_of_median": max_targets(m.configs),
        "runtime_within_1.5x_of_fixed": {
            key: {"worst": max(ratios.values()), "met": max(ratios.values()) <= 1.5}
            for key, ratios in d.runtime_over_fixed.items()
            if ratios
        },
        "float_within_1pct_at_t0_plus_0.1s_1kHz": {
            r["source"]: {"max_rel_error": r["max_rel_error_at"]["0.10"], "met": r["max_rel_error_at"]["0.10"] <= 0.01}
            for r in float_1k
        },
    }


DEFINITIONS = {
    "ns_per_dof_sample_median": "median over 16-sample batches of the mean time per sample, / n; "
    "the lowest of the rounds (round_medians lists all)",
    "p99": "99th percentile of the same batch means, / n",
    "max": "worst single update() over all rounds (steady_clock around one call, clock overhead "
    "subtracted), / n; includes OS interference on this shared machine",
    "max_path": "max over sample index of the min over windows of the single-update time, / n: "
    "the worst data-dependent path with interference filtered out",
    "window_min": "a whole window's batch pass / T, min over windows and rounds: the protocol of "
    "python_run (whole-record run() call / T, min over calls)",
    "instructions_per_dof_sample": "callgrind Ir of the update loop (batch: one record() call) "
    "after 64 warm-up samples (continuous: 400), / (updates n)",
    "numpy_reference_over_python_run_interleaved": "per repetition: the numpy reference (cached "
    "weights) at 1000 and 4000 samples (marginal cost) "
    "and Python run() (min of 5 calls on 2000 samples), "
    "back to back; the ratio of each repetition",
    "batch": "ChainEstimator::record() in 16-sample chunks (median, p99, max = slowest chunk) "
    "and whole windows (window_min), writing every sample's estimates into arrays as the "
    "Python run() does",
}


def meta(args: argparse.Namespace, m: Measurements) -> dict:
    import algid

    return {
        "date": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "command": "python bench/per_sample.py"
        + (" --quick" if args.quick else "")
        + (f" --baseline {args.baseline}" if args.baseline else ""),
        "machine": machine_info(),
        "loadavg_before": m.load_before,
        "loadavg_after": m.load_after,
        "build": {
            "default": "CMAKE_BUILD_TYPE=Release (-O3 -DNDEBUG), no -march: the flags of the "
            "wheel's baseline module algid._core (which adds -fPIC -fvisibility=hidden)",
            "v3": "same plus -march=x86-64-v3 -ffp-contract=off: the flags of algid._core_v3, which "
            "algid imports on CPUs with AVX2/FMA (reported as *_v3)",
            "v4": "same with -march=x86-64-v4: algid._core_v4, imported on CPUs with AVX-512 (reported as *_v4)",
        },
        "python_isa": algid.ISA,
        "signals": "closed-form multisine chain (tests/cpp/closed_form.hpp SineChain), Table 1 for n = 3, 1 kHz",
        "units": "ns per DOF-sample (ns_per_sample_median: per whole sample of all n DOF)",
        "rounds": args.rounds,
        "definitions": DEFINITIONS,
        "continuous": m.continuous_note,
    }


def result_document(args: argparse.Namespace, m: Measurements, d: Derived, targets: dict) -> dict:
    return {
        "meta": meta(args, m),
        "configurations": m.configs,
        "flops": {
            "per_dof_sample": {str(k): v for k, v in d.flops_per_dof.items()},
            "phases": [r for r in m.flops if r["subject"].startswith("phase")],
            "rls_per_dof_sample": d.rls_flops,
        },
        "peak": d.peak,
        "lower_bound": d.bound,
        "ratio_estimator_over_rls": {"time": d.rls_ratio, "instructions": d.rls_ratio_instructions},
        "numpy_reference_over_python_run_interleaved": m.interleaved,
        "runtime_over_fixed": d.runtime_over_fixed,
        "after_over_before": {"baseline": args.baseline, "ratios": d.after_over_before},
        "single_precision": m.accuracy,
        "targets": targets,
    }


def print_configurations(m: Measurements) -> None:
    print(
        f"\nns per DOF-sample (median / p99 / max / max_path), instructions per DOF-sample; "
        f"load average {m.load_before[0]:.1f} -> {m.load_after[0]:.1f} on {os.cpu_count()} cores"
    )
    header = f"{'configuration':34s} " + " ".join(f"{'n=' + str(n):>30s}" for n in SIZES)
    print(header)
    for config in sorted(m.configs):
        cells = []
        for n in SIZES:
            f = m.configs[config].get(str(n))
            if not f:
                cells.append(f"{'-':>30s}")
                continue
            parts = [f"{f['ns_per_dof_sample_median']:.0f}"]
            for key in ("p99", "max", "max_path"):
                parts.append(f"{f[key]:.0f}" if f.get(key) is not None else "-")
            ins = f.get("instructions_per_dof_sample")
            cells.append(f"{'/'.join(parts) + (f' [{ins:.0f}i]' if ins else ''):>30s}")
        print(f"{config:34s} " + " ".join(cells))


def print_flops_and_peak(d: Derived) -> None:
    print(
        "\nflops per DOF-sample (counted): "
        + ", ".join(f"n={n}: {d.flops_per_dof[n]['flops_per_dof_sample']:.0f}" for n in SIZES if n in d.flops_per_dof)
        + f"; RLS: {d.rls_flops:.0f}"
    )
    for name, p in d.peak.items():
        print(
            f"peak ({name}, {p['isa']}): double {p['double_gflops']:.1f} GFLOP/s "
            f"(scalar {p['double_scalar_gflops']:.1f}), float {p['float_gflops']:.1f} GFLOP/s"
        )
    b3 = d.bound["3"]
    print(
        "lower bound n=3: "
        + ", ".join(f"{k[9:]} {v:.0f} ns" for k, v in b3.items() if k.startswith("bound_ns"))
        + f"; measured {b3['measured_ns']:.0f} ns ({b3.get('achieved_gflops', 0):.1f} GFLOP/s achieved)"
    )


def print_ratios(label: str, by_key: dict[str, dict]) -> None:
    """One line of ratios per configuration key: `key: n=1 0.98x, n=3 ...; key: ...`."""
    print(
        label
        + "; ".join(
            f"{key}: " + ", ".join(f"n={n} {r:.2f}x" for n, r in ratios.items())
            for key, ratios in by_key.items()
            if ratios
        )
    )


def print_speed_targets(t: dict, d: Derived) -> None:
    import algid

    print("\ntargets (issue 5):")
    print(
        f"  median n=3 <= 100 ns/DOF-sample: {t['median_ns_per_dof_sample_n3_le_100']['value']:.0f} ns -> "
        f"{'met' if t['median_ns_per_dof_sample_n3_le_100']['met'] else 'NOT met'}"
    )
    lin = t["linear_in_n_n50_per_dof_le_n3"]
    print(
        f"  linear in n (n=50 per DOF <= n=3): {lin['n50']:.0f} vs {lin['n3']:.0f} -> {'met' if lin['met'] else 'NOT met'}"
    )
    print(
        f"  Python run() ({algid.ISA} build) / C++ {d.run_cpp} (whole record, min over repetitions): "
        + ", ".join(
            f"n={n}: {v['ratio']:.2f}x{'' if v['met'] else ' (NOT met)'}"
            for n, v in t["python_run_within_1.5x_of_cpp"].items()
        )
    )
    numpy = t["python_run_at_least_50x_faster_than_numpy_reference"]
    print(
        "  numpy reference / Python run(), back to back (median | min over repetitions): "
        + ", ".join(
            f"n={n}: {v['ratio_interleaved_median']:.0f}x | {v['ratio_interleaved_min']:.0f}x" for n, v in numpy.items()
        )
    )
    print(
        "  (timed apart: marginal | whole call: "
        + ", ".join(
            f"n={n}: {v['ratio_marginal_cached']:.0f}x | {v['ratio_whole_call_cached']:.0f}x" for n, v in numpy.items()
        )
        + ")"
    )


def print_targets(args: argparse.Namespace, m: Measurements, d: Derived, t: dict) -> None:
    print_speed_targets(t, d)
    print(
        "  max / median (raw | path): "
        + ", ".join(
            f"n={n}: {v['max_over_median']:.1f} | {v['max_path_over_median']:.2f}"
            for n, v in t["max_within_5x_of_median"].items()
        )
    )
    print("  estimator / RLS per DOF-sample: " + ", ".join(f"n={n}: {r:.1f}x" for n, r in d.rls_ratio.items()))
    print(
        "  float at t0 + 0.1 s, 1 kHz: "
        + ", ".join(
            f"{src}: {v['max_rel_error']:.1e}" for src, v in t["float_within_1pct_at_t0_plus_0.1s_1kHz"].items()
        )
    )
    print(f"  continuous configuration: {m.continuous_note}")
    print_ratios("  run-time sized / fixed-size, same n: ", d.runtime_over_fixed)
    if d.after_over_before:
        print_ratios(f"  after / before ({args.baseline}), median ns per DOF-sample: ", d.after_over_before)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    load_before = os.getloadavg()
    builds = build_benches(args)
    measured = measure(args, builds, load_before)
    derived = derive(measured, builds)
    targets = issue5_targets(measured, derived)
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(json.dumps(result_document(args, measured, derived, targets), indent=1) + "\n")
    print_configurations(measured)
    print_flops_and_peak(derived)
    print_targets(args, measured, derived, targets)
    print(f"\nwrote {args.output.relative_to(ROOT) if args.output.is_relative_to(ROOT) else args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
