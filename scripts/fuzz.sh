#!/usr/bin/env bash
# The fuzzing campaign of sepg (not run in CI): every libFuzzer target of fuzz/, one after
# another, single process each, RUNS executions per target (default 10 million).
#
#   scripts/fuzz.sh                      # bounds, estimators, config; 1e7 runs each
#   RUNS=100000 scripts/fuzz.sh config   # a quick run of one target
#
# Installs cargo-fuzz if it is missing. libFuzzer needs unstable rustc flags: on a stable
# toolchain they are enabled with RUSTC_BOOTSTRAP=1 (nothing else changes). The targets are
# built in release mode with debug assertions (integer overflow checks) and without a
# sanitizer: the code under test is safe Rust, and the campaign looks for panics and
# non-finite results, which the targets assert. Corpora, crash artifacts and logs go under
# $FUZZ_DIR (default target/fuzz-campaign); a crash stops its target and the script exits 1.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
runs="${RUNS:-10000000}"
work="${FUZZ_DIR:-$root/target/fuzz-campaign}"
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(bounds estimators config)

if ! cargo fuzz --version >/dev/null 2>&1; then
    cargo install cargo-fuzz --locked
fi
if ! rustc -V | grep -q nightly; then
    export RUSTC_BOOTSTRAP=1
fi

flags=(--release --debug-assertions --sanitizer none --target-dir "$work/build")
mkdir -p "$work"
cd "$root/fuzz"
status=0
for t in "${targets[@]}"; do
    corpus="$work/corpus/$t"
    artifacts="$work/artifacts/$t/"
    mkdir -p "$corpus" "$artifacts"
    if [ -d "seeds/$t" ]; then
        cp -n "seeds/$t"/* "$corpus"/ 2>/dev/null || true
    fi
    log="$work/$t.log"
    echo "fuzzing $t: $runs runs (log: $log)"
    if cargo fuzz run "${flags[@]}" "$t" "$corpus" -- \
        -runs="$runs" -max_len=1024 -timeout=10 -print_final_stats=1 \
        -artifact_prefix="$artifacts" >"$log" 2>&1; then
        grep -a "^Done" "$log" | tail -1 | sed "s/^/  $t: /"
    else
        echo "  $t: FAILED, see $log and $artifacts"
        status=1
    fi
done
exit $status
