#!/usr/bin/env python3
"""The true curvature of J on the clipped `lqg` preset at gamma = 0, against the penalties c
(Theorem 4.2) and d (Theorem 4.3) of the thesis: the figures of docs/ERRATA.md section 27.

At gamma = 0 only the first reward counts. With s0 ~ U[-2, 2], a ~ N(v s0, sigma^2),
sigma = e^w, and r = -(s0^2 + clip(a, -2, 2)^2) / 2:

  J(v, w) = -(E[s0^2] + E[f(v s0)]) / 2,   f(mu) = E[clip(mu + sigma z, -2, 2)^2]
  f(mu)   = (mu^2 + sigma^2)(Phi(b) - Phi(a)) + 2 mu sigma (phi(a) - phi(b))
            + sigma^2 (a phi(a) - b phi(b)) + 4 (Phi(a) + 1 - Phi(b)),
  a = (-2 - mu)/sigma, b = (2 - mu)/sigma,

and, since d^2/dx^2 clip(x)^2 = 2 [|x| < 2] - 4 delta(x - 2) - 4 delta(x + 2),

  d^2J/dv^2 = -E[s0^2 f''(v s0)] / 2,   f''(mu) = 2 (Phi(b) - Phi(a)) - 4 (phi(a) + phi(b)) / sigma.

d^2J/dw^2 is a central second difference of J in w (step 1e-3, error ~1e-7 here); the
expectations over s0 use composite Simpson's rule with 2000 intervals. d^2J/dv^2 is also
checked against the second difference of J in v.

At gamma = 0, c = R M_phi^2 |A| / (sqrt(2 pi) sigma^3) and d = R psi |A| / (2 sigma) have no other
term (R = 4, M_phi = 2, |A| = 4 on `lqg`). Along the gradient, the v-bound
alpha g^2 - alpha^2 c g^2 holds for every step iff -d^2J/dv^2 / 2 <= c everywhere, and the
w-bound beta g^2 - beta^2 d g^2 iff -d^2J/dw^2 / 2 <= d (Taylor's theorem): the printed
columns are the largest -d^2J/dv^2 / 2 over v in [-5, 5] as a fraction of c, and likewise for
w and d. The same fractions hold on `lqg1d` at 2 sigma (s -> 2s maps one preset onto the
other and scales J, its derivatives in (v, w), c and d by 7.2).

The clipped DP oracle gives the same second derivatives:
`sepg exact --env lqg --v V --sigma S --horizon 1 --clipped` (H = 1 is gamma = 0) prints the
Hessian in (v, w).

Usage: python3 scripts/lqg_gamma0_curvature.py   (standard library only, about a minute)
"""

import math

R, M_PHI, ACTION_VOLUME = 4.0, 2.0, 4.0
PSI = 0.523557
K_W = 1.8321260494037879


def cdf(x):
    return 0.5 * math.erfc(-x / math.sqrt(2.0))


def pdf(x):
    return math.exp(-0.5 * x * x) / math.sqrt(2.0 * math.pi)


def f(mu, sigma):
    a, b = (-2.0 - mu) / sigma, (2.0 - mu) / sigma
    return ((mu * mu + sigma * sigma) * (cdf(b) - cdf(a)) + 2.0 * mu * sigma * (pdf(a) - pdf(b))
            + sigma * sigma * (a * pdf(a) - b * pdf(b)) + 4.0 * (cdf(a) + 1.0 - cdf(b)))


def f_mumu(mu, sigma):
    a, b = (-2.0 - mu) / sigma, (2.0 - mu) / sigma
    return 2.0 * (cdf(b) - cdf(a)) - 4.0 * (pdf(a) + pdf(b)) / sigma


def expect_s0(g, n=2000):
    """E[g(s0)] for s0 ~ U[-2, 2] by composite Simpson's rule."""
    h = 4.0 / n
    total = sum((1 if i in (0, n) else 4 if i % 2 else 2) * g(-2.0 + i * h) for i in range(n + 1))
    return total * h / 3.0 / 4.0


def j(v, w):
    sigma = math.exp(w)
    return -0.5 * (4.0 / 3.0 + expect_s0(lambda s: f(v * s, sigma)))


def j_vv(v, sigma):
    return -0.5 * expect_s0(lambda s: s * s * f_mumu(v * s, sigma))


def second_difference(g, x, h=1e-3):
    return (g(x + h) - 2.0 * g(x) + g(x - h)) / (h * h)


def c(sigma):
    return R * M_PHI ** 2 * ACTION_VOLUME / (math.sqrt(2.0 * math.pi) * sigma ** 3)


def d(sigma):
    return R * PSI * ACTION_VOLUME / (2.0 * sigma)


def main():
    thresholds = {
        "(c threshold)": ACTION_VOLUME * math.sqrt(math.e) / 4.0,
        "(d threshold)": PSI * ACTION_VOLUME / K_W,
    }
    sigmas = list(thresholds.items()) + [("", s) for s in (2.0, 3.0, 4.0)]
    vs = [i / 10.0 for i in range(-50, 51)]
    print("| sigma | c | max -J_vv/2 (at v) | / c | d | max -J_ww/2 (at v) | / d |")
    print("|---|---|---|---|---|---|---|")
    for label, sigma in sigmas:
        vv, v_at = min((j_vv(v, sigma), v) for v in vs)
        check = second_difference(lambda x: j(x, math.log(sigma)), v_at)
        assert abs(check - vv) < 1e-5 * abs(vv), (sigma, v_at, vv, check)
        ww, w_at = min((second_difference(lambda w: j(v, w), math.log(sigma)), v) for v in vs)
        print(f"| {sigma:.4f} {label} | {c(sigma):.4f} | {-vv / 2:.4f} ({v_at:+.1f}) | "
              f"{-vv / 2 / c(sigma):.1%} | {d(sigma):.4f} | {-ww / 2:.4f} ({w_at:+.1f}) | "
              f"{-ww / 2 / d(sigma):.1%} |", flush=True)


if __name__ == "__main__":
    main()
