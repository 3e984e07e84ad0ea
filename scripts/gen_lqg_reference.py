#!/usr/bin/env python3
"""Generate the high-precision reference tables of the sepg-mdp exact-oracle tests.

1. normal_cdf.csv: the standard normal CDF Phi(z) = erfc(-z/sqrt(2))/2 at 50 significant
   digits, for z on a grid covering the deep lower tail (z = -38) to the upper tail. Each z is
   the exact binary64 value the Rust test reads back.

2. lqg_scalar.csv: J and its derivatives for the *unclipped* scalar presets (A = B = 1,
   Q = R = q, s0 ~ U[-b, b], gamma = 0.99, no transition noise) under the policy
   a ~ N(v s, sigma^2), sigma = e^w:
       X_0 = b^2/3,  X_{t+1} = (1 + v)^2 X_t + sigma^2,
       J_H = -sum_{t<H} gamma^t [ q (1 + v^2) X_t + q sigma^2 ],
   and, for H = inf, the geometric limits
       P = q (1 + v^2) / (1 - gamma (1 + v)^2),
       J = -P (b^2/3 + gamma sigma^2/(1 - gamma)) - q sigma^2/(1 - gamma).
   The derivatives dJ/dv, dJ/dw and d2J/dw dv are computed by mpmath.diff (high-precision
   finite differences at 50 digits). The rows with w = -inf are the deterministic policy,
   and the first rows of each preset are the optimum v* = (1 - sqrt(1 + 4 gamma^2))/(2 gamma).

Every value is written rounded to 17 significant digits (binary64 round trip).

Usage: python3 scripts/gen_lqg_reference.py crates/mdp/tests/data
Requires: mpmath (pip install mpmath).
"""

import os
import sys

import mpmath as mp

mp.mp.dps = 50

GAMMA = mp.mpf("0.99")
PRESETS = {"lqg": (mp.mpf("0.5"), mp.mpf(2)), "lqg1d": (mp.mpf("0.9"), mp.mpf(4))}


def fmt(x):
    return mp.nstr(x, 17, min_fixed=0, max_fixed=0, strip_zeros=False)


def phi(z):
    return mp.erfc(-mp.mpf(z) / mp.sqrt(2)) / 2


def j_value(preset, v, w, horizon):
    q, b = PRESETS[preset]
    s2 = mp.mpf(0) if w == -mp.inf else mp.e ** (2 * w)
    x0 = b * b / 3
    lam2 = (1 + v) ** 2
    if horizon == "inf":
        p = q * (1 + v * v) / (1 - GAMMA * lam2)
        return -p * (x0 + GAMMA * s2 / (1 - GAMMA)) - q * s2 / (1 - GAMMA)
    total, x, disc = mp.mpf(0), x0, mp.mpf(1)
    for _ in range(horizon):
        total -= disc * (q * (1 + v * v) * x + q * s2)
        x = lam2 * x + s2
        disc *= GAMMA
    return total


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "crates/mdp/tests/data"
    os.makedirs(out, exist_ok=True)

    zs = [k * 0.25 for k in range(-152, 35)] + [-1e-9, 1e-9, 0.1, -0.3, 1.7, -5.5, 0.6744897501960817]
    with open(os.path.join(out, "normal_cdf.csv"), "w") as f:
        f.write("z,phi\n")
        for z in zs:
            f.write(f"{z!r},{fmt(phi(z))}\n")

    v_star = (1 - mp.sqrt(1 + 4 * GAMMA**2)) / (2 * GAMMA)
    points = [(v_star, -mp.inf, "inf"), (v_star, mp.mpf(0), "inf")]
    for v in ["-0.1", "-0.6", "-1.2"]:
        for w in [mp.log(mp.mpf("0.2")), mp.mpf(0), -mp.inf]:
            for h in [1, 20, "inf"]:
                points.append((mp.mpf(v), w, h))
    with open(os.path.join(out, "lqg_scalar.csv"), "w") as f:
        f.write("preset,v,w,horizon,j,dj_dv,dj_dw,d2j_dw_dv\n")
        for preset in PRESETS:
            for v, w, h in points:
                v = mp.mpf(float(v))
                w = w if w == -mp.inf else mp.mpf(float(w))
                j = j_value(preset, v, w, h)
                djv = mp.diff(lambda x: j_value(preset, x, w, h), v)
                if w == -mp.inf:
                    djw, dwv, wstr = mp.mpf(0), mp.mpf(0), "-inf"
                else:
                    djw = mp.diff(lambda y: j_value(preset, v, y, h), w)
                    dwv = mp.diff(lambda x, y: j_value(preset, x, y, h), (v, w), (1, 1))
                    wstr = repr(float(w))
                f.write(
                    f"{preset},{float(v)!r},{wstr},{h},{fmt(j)},{fmt(djv)},{fmt(djw)},{fmt(dwv)}\n"
                )


if __name__ == "__main__":
    main()
