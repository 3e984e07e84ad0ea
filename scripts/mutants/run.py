#!/usr/bin/env python3
"""Mutation runner: applies each mutant of scripts/mutants/*.mutant in turn to a scratch copy
of the repository and runs the relevant parts of the CI suite against it.

A mutant file names the crate whose tests run first, a path hint, and one exact text
replacement:

    # what: one line describing the bug
    # crate: sepg-bounds
    # file: crates/bounds/src/constants.rs
    @@ from
    <exact text, one or more lines>
    @@ to
    <replacement>

The text is looked up in the hinted file first; if the file moved or the text is not there
exactly once, every Rust source file of the workspace is searched for a unique occurrence
(so mutants survive code moves). A mutant whose text is found nowhere, or more than once, is
reported as "does not apply" and is not counted in the kill rate.

Stages, stopping at the first that fails (the mutant is then "killed" by that stage):

    1. cargo test --release -p <crate>                     (the crate's own tests and doctests)
    2. sepg verify --quick                                 (exit status 1 = a check differs)
    3. cargo test --release -p <each crate that depends on it>
       (the root package's CLI tests only for mutants of the CLI itself, as the other crates
       are exercised there through the same code paths the crate tests cover)

A mutant that does not compile is reported as "does not compile" (not counted). Each line of
the output and each row of the table names the stage that killed the mutant and the failing
tests (or, for `sepg verify --quick`, the checks whose outcome changed), so a mutant caught only
by a single-seed performance test can be spotted. cargo stops at the first test binary that
fails (the unit tests run first); --no-fail-fast runs every test binary of the stage and lists
every failing test, at a higher cost.

The scratch copy lives in --work (default /tmp/sepg-mutation): the working tree's tracked and
untracked files (git ls-files) are copied to WORK/src, and WORK/target starts as a copy of the repository's
release target/ so that dependencies are not rebuilt. Run it niced, in the background:

    nice -n 10 python3 scripts/mutants/run.py > mutation.log 2>&1 &

Options: --only ID[,ID...] (prefixes of the mutant file names), --no-fail-fast, --timeout SECONDS per stage
(default 2400; a stage that times out kills the mutant), --out FILE (markdown table, default
WORK/results.md), --no-baseline (skip the unmutated run that must pass first).
Requires python3 and the Rust toolchain.
"""

import argparse
import glob
import os
import re
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", ".."))
SOURCE_DIRS = ["crates", "src", "verification", "benches"]


def parse_mutant(path):
    text = open(path, encoding="utf-8").read()
    meta = dict(re.findall(r"^# (\w+): (.*)$", text, flags=re.M))
    m = re.search(r"^@@ from\n(.*?)\n@@ to\n(.*?)\n?\Z", text, flags=re.S | re.M)
    if not m:
        raise ValueError(f"{path}: malformed mutant")
    return {
        "id": os.path.basename(path)[: -len(".mutant")],
        "what": meta.get("what", ""),
        "crate": meta["crate"],
        "file": meta["file"],
        "from": m.group(1),
        "to": m.group(2),
    }


def copy_tree(dest):
    """Copies the repository's tracked and untracked (not ignored) files to dest, keeping
    modification times (so that cargo does not rebuild unchanged crates)."""
    listed = subprocess.run(["git", "ls-files", "-co", "--exclude-standard", "-z"], cwd=REPO,
                            check=True, capture_output=True).stdout.decode().split("\0")
    if os.path.exists(dest):
        shutil.rmtree(dest)
    for rel in filter(None, listed):
        s = os.path.join(REPO, rel)
        if not os.path.isfile(s):
            continue
        d = os.path.join(dest, rel)
        os.makedirs(os.path.dirname(d), exist_ok=True)
        shutil.copy2(s, d)


def rust_files(root):
    for d in SOURCE_DIRS:
        for p in glob.glob(os.path.join(root, d, "**", "*.rs"), recursive=True):
            yield p


def locate(root, mutant):
    """The file holding mutant['from'] exactly once (hint first), or None."""
    hint = os.path.join(root, mutant["file"])
    if os.path.exists(hint) and open(hint, encoding="utf-8").read().count(mutant["from"]) == 1:
        return hint
    hits = []
    for p in rust_files(root):
        n = open(p, encoding="utf-8").read().count(mutant["from"])
        if n:
            hits.append((p, n))
    if len(hits) == 1 and hits[0][1] == 1:
        return hits[0][0]
    return None


def run(cmd, cwd, env, timeout, log):
    start = time.time()
    log.write(f"$ {' '.join(cmd)}\n")
    log.flush()
    try:
        p = subprocess.run(cmd, cwd=cwd, env=env, timeout=timeout, capture_output=True, text=True)
    except subprocess.TimeoutExpired:
        log.write("timeout\n")
        return None, "", time.time() - start
    out = p.stdout + p.stderr
    log.write(out[-20000:])
    log.flush()
    return p.returncode, out, time.time() - start


def failing_tests(output):
    names = re.findall(r"^test (.+?) \.\.\. FAILED$", output, flags=re.M)
    return sorted(set(names))


def compile_error(output):
    return re.search(r"^error(\[E\d+\])?: ", output, flags=re.M) is not None and \
        "error: test failed" not in output and "test result:" not in output


# Workspace crates that depend on each crate (tests run in stage 3).
DEPENDENTS = {
    "sepg-bounds": ["sepg-estimators", "sepg-algo", "sepg-verification"],
    "sepg-mdp": ["sepg-estimators", "sepg-algo", "sepg-verification"],
    "sepg-estimators": ["sepg-algo", "sepg-verification"],
    "sepg-algo": ["sepg-verification"],
    "sepg-verification": [],
    "sepg-runs": ["sepg"],
}


def stages(mutant, no_fail_fast=False):
    crate = mutant["crate"]
    extra = ["--no-fail-fast"] if no_fail_fast else []
    out = [
        ("crate tests", ["cargo", "test", "--release", "-p", crate] + extra),
        ("verify --quick", None),
    ]
    deps = DEPENDENTS.get(crate, [])
    if deps:
        cmd = ["cargo", "test", "--release"] + extra
        for d in deps:
            cmd += ["-p", d]
        out.append(("dependent crates' tests", cmd))
    return out


def run_stage(name, cmd, src, env, timeout, log):
    """(status, detail, seconds): status in {'pass', 'fail', 'timeout', 'compile'}."""
    if cmd is None:  # sepg verify --quick
        code, out, secs = run(["cargo", "build", "--release", "--bin", "sepg"], src, env, timeout, log)
        if code is None:
            return "timeout", "", secs
        if code != 0:
            return "compile", "", secs
        code, out, s2 = run([os.path.join(env["CARGO_TARGET_DIR"], "release", "sepg"), "verify",
                             "--quick", "--quiet"], src, env, timeout, log)
        secs += s2
        if code is None:
            return "timeout", "", secs
        if code == 0:
            return "pass", "", secs
        differing = re.findall(r"^CHANGED\s+(\S+)", out, flags=re.M)
        return "fail", ", ".join(sorted(set(differing))[:8]) or f"exit {code}", secs
    code, out, secs = run(cmd, src, env, timeout, log)
    if code is None:
        return "timeout", "", secs
    if code == 0:
        return "pass", "", secs
    tests = failing_tests(out)
    if not tests and compile_error(out):
        return "compile", "", secs
    return "fail", ", ".join(tests[:8]) + (" …" if len(tests) > 8 else ""), secs


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--work", default="/tmp/sepg-mutation")
    ap.add_argument("--only", default="")
    ap.add_argument("--timeout", type=int, default=2400)
    ap.add_argument("--out", default="")
    ap.add_argument("--no-baseline", action="store_true")
    ap.add_argument("--no-fail-fast", action="store_true")
    args = ap.parse_args()

    work = os.path.abspath(args.work)
    src = os.path.join(work, "src")
    os.makedirs(work, exist_ok=True)
    copy_tree(src)
    target = os.path.join(work, "target")
    if not os.path.exists(target) and os.path.exists(os.path.join(REPO, "target", "release")):
        os.makedirs(target)
        subprocess.run(["cp", "-a", os.path.join(REPO, "target", "release"), target], check=True)
    env = dict(os.environ, CARGO_TARGET_DIR=target, CARGO_TERM_COLOR="never")
    log = open(os.path.join(work, "mutation.log"), "a", encoding="utf-8")

    mutants = [parse_mutant(p) for p in sorted(glob.glob(os.path.join(HERE, "*.mutant")))]
    if args.only:
        wanted = args.only.split(",")
        mutants = [m for m in mutants if any(m["id"].startswith(w) for w in wanted)]

    if not args.no_baseline:
        for name, cmd in stages({"crate": "sepg-verification"}, args.no_fail_fast):
            status, detail, secs = run_stage(name, cmd, src, env, args.timeout, log)
            print(f"baseline {name}: {status} ({secs:.0f} s) {detail}", flush=True)
            if status != "pass":
                sys.exit("the unmutated code does not pass; fix that first")

    rows = []
    for m in mutants:
        path = locate(src, m)
        if path is None:
            rows.append((m, "does not apply", "", "", 0.0))
            print(f"{m['id']}: does not apply", flush=True)
            continue
        original = open(path, encoding="utf-8").read()
        open(path, "w", encoding="utf-8").write(original.replace(m["from"], m["to"], 1))
        log.write(f"\n===== {m['id']} ({os.path.relpath(path, src)})\n")
        status, stage, detail, total = "survived", "", "", 0.0
        try:
            for name, cmd in stages(m, args.no_fail_fast):
                st, det, secs = run_stage(name, cmd, src, env, args.timeout, log)
                total += secs
                if st == "compile":
                    status, stage = "does not compile", name
                    break
                if st in ("fail", "timeout"):
                    status, stage, detail = "killed", name, det if st == "fail" else "timeout"
                    break
        finally:
            open(path, "w", encoding="utf-8").write(original)
        rows.append((m, status, stage, detail, total))
        by = f" at stage '{stage}' by: {detail}" if status == "killed" else ""
        print(f"{m['id']}: {status}{by} ({total:.0f} s)", flush=True)

    counted = [r for r in rows if r[1] in ("killed", "survived")]
    killed = sum(1 for r in counted if r[1] == "killed")
    lines = [
        f"Mutants: {len(rows)}; applied and compiled: {len(counted)}; killed: {killed}; "
        f"kill rate: {killed}/{len(counted)}"
        + (f" = {100.0 * killed / len(counted):.0f}%" if counted else ""),
        "",
        "| mutant | crate | bug | result | killed at stage | by (failing tests / changed checks) |",
        "|---|---|---|---|---|---|",
    ]
    for m, status, stage, detail, _ in rows:
        lines.append(f"| `{m['id']}` | {m['crate']} | {m['what']} | {status} | {stage} | "
                     f"{detail.replace('|', '/')} |")
    report = "\n".join(lines) + "\n"
    out = args.out or os.path.join(work, "results.md")
    open(out, "w", encoding="utf-8").write(report)
    print(report)


if __name__ == "__main__":
    main()
