"""Wall time of the same run through the command line and through the Python API, each as a
whole process (interpreter start-up and imports included), alternated and repeated; prints
the median of each and their ratio.

    cargo build --release && .venv/bin/python crates/python/benches/run_overhead.py
"""

import argparse
import pathlib
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[3]


def timed(cmd):
    start = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    return time.perf_counter() - start


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--iterations", type=int, default=5000)
    p.add_argument("--env", default="lqg1d")
    p.add_argument("--algo", default="sepg-zv")
    a = p.parse_args()
    options = dict(env=a.env, algo=a.algo, iterations=a.iterations, batch=100, seed=1)
    flags = [x for k, v in options.items() for x in (f"--{k}", str(v))]
    tmp = pathlib.Path(tempfile.mkdtemp())
    cli, py = [], []
    for i in range(a.repeats):
        for name, out in (("cli", cli), ("py", py)):
            d = tmp / f"{name}-{i}"
            if name == "cli":
                cmd = [str(ROOT / "target/release/sepg"), "run", "--quiet", "--out", str(d), *flags]
            else:
                cmd = [sys.executable, "-c",
                       f"import sepg.runs; sepg.runs.run({str(d)!r}, **{options!r})"]
            out.append(timed(cmd))
            shutil.rmtree(d)
    c, q = statistics.median(cli), statistics.median(py)
    print(f"{a.env} {a.algo}, {a.iterations} iterations of N = 100, median of {a.repeats}:")
    print(f"command line {c:.3f} s, Python API {q:.3f} s, ratio {q / c:.3f}")


if __name__ == "__main__":
    main()
