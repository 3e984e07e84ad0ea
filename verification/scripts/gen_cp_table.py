#!/usr/bin/env python3
"""Reference table of one-sided Clopper-Pearson bounds, computed with mpmath at 50 digits.

Output: verification/tests/data/clopper_pearson.csv with columns
successes, trials, confidence, upper, lower
where upper = Beta^-1(confidence; k+1, n-k) (1 if k = n) and
lower = Beta^-1(1-confidence; k, n-k+1) (0 if k = 0), each printed with 17 significant digits.
The quantile is found by bisection, evaluating the regularised incomplete beta function for
integer parameters through the binomial identity I_x(k+1, n-k) = P(Bin(n, x) >= k+1).

Usage: python3 verification/scripts/gen_cp_table.py > verification/tests/data/clopper_pearson.csv
"""
import mpmath

mpmath.mp.dps = 50


def binom_cdf(k, n, x):
    """P(Bin(n, x) <= k), summed exactly at the working precision."""
    return mpmath.fsum(mpmath.binomial(n, j) * x**j * (1 - x) ** (n - j) for j in range(k + 1))


def solve(f, target):
    """x in [0, 1] with f(x) = target for a decreasing f, by 200 bisection steps."""
    lo, hi = mpmath.mpf(0), mpmath.mpf(1)
    for _ in range(200):
        mid = (lo + hi) / 2
        if f(mid) > target:
            lo = mid
        else:
            hi = mid
    return (lo + hi) / 2


def upper(k, n, conf):
    """Beta^-1(conf; k+1, n-k): P(Bin(n, p) <= k) = 1 - conf."""
    if k == n:
        return mpmath.mpf(1)
    return solve(lambda x: binom_cdf(k, n, x), 1 - mpmath.mpf(conf))


def lower(k, n, conf):
    """Beta^-1(1-conf; k, n-k+1): P(Bin(n, p) <= k-1) = conf."""
    if k == 0:
        return mpmath.mpf(0)
    return solve(lambda x: binom_cdf(k - 1, n, x), mpmath.mpf(conf))


CASES = [
    (0, 1), (1, 1), (0, 10), (1, 10), (5, 10), (10, 10), (0, 100), (3, 100), (50, 100),
    (99, 100), (0, 1000), (7, 1000), (500, 1000), (0, 4000), (12, 20000), (1, 100000),
]
CONFIDENCES = ["0.9", "0.95", "0.99", "0.999"]

print("successes,trials,confidence,upper,lower")
for k, n in CASES:
    for c in CONFIDENCES:
        u = mpmath.nstr(upper(k, n, c), 17, min_fixed=0, max_fixed=0)
        l = mpmath.nstr(lower(k, n, c), 17, min_fixed=0, max_fixed=0)
        print(f"{k},{n},{c},{u},{l}")
