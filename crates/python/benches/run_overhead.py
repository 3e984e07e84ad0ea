"""Time of the same run through the command line and through the Python API, each as a whole
process (interpreter start-up and imports included), interleaved and repeated.

Prints, for wall-clock and for CPU time (user + system of the child process from
``getrusage``, to the microsecond, less sensitive to the load of a shared machine), the
median of each path, the median of the per-repetition ratios Python / command line and their
range; then the fixed cost of the Python path on its own: an interpreter that only starts
(``python -c pass``), one that only imports ``sepg.runs``, and the ratio that the bare
interpreter's start-up alone implies.

The package's bytecode is cached first, as an installation does (with PYTHONDONTWRITEBYTECODE
set, as on some CI machines, every start would compile sepg's sources again: about 27 million
instructions, more than half of a bare interpreter's start-up).

    cargo build --release && .venv/bin/python crates/python/benches/run_overhead.py
"""

import argparse
import os
import pathlib
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[3]


def children_cpu():
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def timed(cmd):
    """(wall-clock seconds, CPU seconds) of the process `cmd`."""
    before = children_cpu()
    start = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    return wall, children_cpu() - before


def report(name, cli, py):
    ratios = sorted(q / c for c, q in zip(cli, py))
    print(
        f"{name:>5}: command line {statistics.median(cli):.4f} s, Python API {statistics.median(py):.4f} s; "
        f"ratio median {statistics.median(ratios):.3f}, range {ratios[0]:.3f}-{ratios[-1]:.3f}"
    )


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--repeats", type=int, default=15)
    p.add_argument("--iterations", type=int, default=10000)
    p.add_argument("--env", default="lqg1d")
    p.add_argument("--algo", default="sepg-zv")
    a = p.parse_args()
    options = dict(env=a.env, algo=a.algo, iterations=a.iterations, batch=100, seed=1)
    flags = [x for k, v in options.items() for x in (f"--{k}", str(v))]
    tmp = pathlib.Path(tempfile.mkdtemp())
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    subprocess.run([sys.executable, "-c", "import sepg.runs"], check=True, env=env)
    times = {"cli": [], "py": [], "start": [], "import": []}
    for i in range(a.repeats):
        for name in times:
            d = tmp / f"{name}-{i}"
            if name == "cli":
                cmd = [str(ROOT / "target/release/sepg"), "run", "--quiet", "--out", str(d), *flags]
            elif name == "py":
                cmd = [sys.executable, "-c", f"import sepg.runs; sepg.runs.run({str(d)!r}, **{options!r})"]
            elif name == "start":
                cmd = [sys.executable, "-c", "pass"]
            else:
                cmd = [sys.executable, "-c", "import sepg.runs"]
            times[name].append(timed(cmd))
            shutil.rmtree(d, ignore_errors=True)
    print(f"{a.env} {a.algo}, {a.iterations} iterations of N = 100, {a.repeats} interleaved repetitions:")
    for k, label in ((0, "wall"), (1, "CPU")):
        report(label, [t[k] for t in times["cli"]], [t[k] for t in times["py"]])
    for k, label in ((0, "wall"), (1, "CPU")):
        start = statistics.median(t[k] for t in times["start"])
        imp = statistics.median(t[k] for t in times["import"])
        cli = statistics.median(t[k] for t in times["cli"])
        print(
            f"{label:>5}: python -c pass {start:.4f} s, python -c 'import sepg.runs' {imp:.4f} s; "
            f"the bare interpreter alone makes the ratio at least 1 + {start:.4f}/{cli:.4f} = {1 + start / cli:.3f}"
        )


if __name__ == "__main__":
    main()
