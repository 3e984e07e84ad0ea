#!/usr/bin/env bash
# Whole-process comparison of `sepg estimate` with the fused-loop reference
# (benches/examples/fused_estimate.rs) on lqg1d, N = 2e6, H = 20, side by side in one
# hyperfine run, and the maximum resident memory of both (and of `sepg estimate` at N = 1e8).
# Report the ratio of the mean times, not the times: the machine may be shared.
#
#   scripts/perf-estimate.sh            # needs hyperfine and GNU time (/usr/bin/time)
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
cargo build --release --quiet -p sepg-benches --example fused_estimate
sepg=target/release/sepg
fused=target/release/examples/fused_estimate
n=${N:-2000000}
hyperfine -N --warmup 1 --runs "${RUNS:-10}" \
  "$fused $n 20 -0.3 0.5 1" \
  "$sepg estimate --env lqg1d --v -0.3 --sigma 0.5 --horizon 20 --n $n --seed 1 --json"
for cmd in "$fused $n 20 -0.3 0.5 1" \
  "$sepg estimate --env lqg1d --v -0.3 --sigma 0.5 --horizon 20 --n $n --seed 1 --json" \
  "$sepg estimate --env lqg1d --v -0.3 --sigma 0.5 --horizon 20 --n 100000000 --seed 1 --json"; do
  /usr/bin/time -f "%M kB max RSS, %U s user, %S s sys: $cmd" $cmd > /dev/null
done
