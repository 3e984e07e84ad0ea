#!/usr/bin/env python3
"""Generate the Gaussian curvature constants used by the rigorous bounds of sepg-bounds.

For a Gaussian policy density pi(a) = phi(z)/sigma, z = (a - mu)/sigma, sigma = e^w, on the
whole real line (the clipped presets sample actions on R and clip them afterwards):

  d^2 pi / d mu^2 = (z^2 - 1) phi(z) / sigma^3
  d^2 pi / d w^2  = (z^4 - 4 z^2 + 1) phi(z) / sigma

so the L1 norms over R are scale-free up to the powers of sigma:

  K_MU = sigma^2 * int_R |d^2 pi/d mu^2| da = int_R |z^2 - 1| phi(z) dz
  K_W  =           int_R |d^2 pi/d w^2|  da = int_R |z^4 - 4 z^2 + 1| phi(z) dz

Both are computed twice at 60 significant digits and must agree: by adaptive quadrature split
at the sign changes (z = 1; z^2 = 2 -+ sqrt(3)), and in closed form from the antiderivatives
-z phi(z) and (z - z^3) phi(z):

  K_MU = 4 phi(1),   K_W = 4 (G(z1) - G(z2)),  G(z) = (z - z^3) phi(z),
  z1 = sqrt(2 - sqrt 3), z2 = sqrt(2 + sqrt 3).

Also written: psi of Lemma A.1 (max of |d^2 pi/d w^2| times sigma), phi(0) = 1/sqrt(2 pi) (max of
|d^2 pi/d mu^2| times sigma^3), and the standard deviations above which the box-based terms
of the thesis (|A| psi / sigma and |A| / (sqrt(2 pi) sigma)) fall below the real-line
constants, for |A| = 4 (lqg) and |A| = 8 (lqg1d).

Values are written rounded to the nearest binary64 (17 significant digits).

Usage: python3 scripts/gen_gaussian_constants.py > crates/bounds/tests/data/gaussian_constants.csv
Requires: mpmath (pip install mpmath).
"""

import mpmath as mp

mp.mp.dps = 60


def phi(z):
    return mp.exp(-z * z / 2) / mp.sqrt(2 * mp.pi)


def main():
    # K_MU
    k_mu_quad = 2 * (mp.quad(lambda z: (1 - z * z) * phi(z), [0, 1])
                     + mp.quad(lambda z: (z * z - 1) * phi(z), [1, mp.inf]))
    k_mu = 4 * phi(mp.mpf(1))
    assert abs(k_mu - k_mu_quad) < mp.mpf(10) ** -50, (k_mu, k_mu_quad)

    # K_W
    z1 = mp.sqrt(2 - mp.sqrt(3))
    z2 = mp.sqrt(2 + mp.sqrt(3))
    f = lambda z: (z ** 4 - 4 * z * z + 1) * phi(z)  # noqa: E731
    k_w_quad = 2 * (mp.quad(f, [0, z1]) - mp.quad(f, [z1, z2]) + mp.quad(f, [z2, mp.inf]))
    g = lambda z: (z - z ** 3) * phi(z)  # noqa: E731
    k_w = 4 * (g(z1) - g(z2))
    assert abs(k_w - k_w_quad) < mp.mpf(10) ** -50, (k_w, k_w_quad)

    # psi of Lemma A.1: |chi^2 - 4 chi + 1| e^{-chi/2}/sqrt(2 pi) at chi = 4 - sqrt(7)
    chi = 4 - mp.sqrt(7)
    psi = abs(chi * chi - 4 * chi + 1) * mp.exp(-chi / 2) / mp.sqrt(2 * mp.pi)
    grid = max(abs((c * c - 4 * c + 1) * mp.exp(-c / 2)) for c in
               [mp.mpf(i) / 1000 for i in range(0, 20001)]) / mp.sqrt(2 * mp.pi)
    assert grid <= psi and psi - grid < mp.mpf(10) ** -6

    rows = [
        ("k_mu", k_mu),
        ("k_w", k_w),
        ("psi", psi),
        ("phi0", phi(mp.mpf(0))),
    ]
    for volume in (4, 8):
        rows.append((f"sigma_threshold_w_volume_{volume}", volume * psi / k_w))
        rows.append((f"sigma_threshold_c_volume_{volume}",
                     volume / (mp.sqrt(2 * mp.pi) * k_mu)))
    print("name,value")
    for name, value in rows:
        print(f"{name},{mp.nstr(value, 17, min_fixed=-5, max_fixed=5)}")


if __name__ == "__main__":
    main()
