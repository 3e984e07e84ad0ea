"""The certified steps, interval arithmetic, the exploring w-update and the rigorous
constants of ``sepg.bounds``, against values computed here independently: numerical
integrals, closed forms by hand, 50-digit decimal arithmetic, and the command line's
``sepg bounds --json --certified``."""

import json
import math
import pathlib
import subprocess
from decimal import Decimal, getcontext
from fractions import Fraction

import numpy as np
import pytest

import sepg
from sepg import _native, bounds

ROOT = pathlib.Path(__file__).resolve().parents[3]
CLI = ROOT / "target" / "release" / "sepg"
K = sepg.TaskConstants(0.9, 2.0, 1.5, 3.0)

getcontext().prec = 50
# pi to 50 digits, so that sqrt(2 pi) and c(sigma) are known far beyond double precision.
PI = Decimal("3.14159265358979323846264338327950288419716939937510")


def simpson(f, a, b, n=20000):
    x = np.linspace(a, b, n + 1)
    y = f(x)
    return (b - a) / (3 * n) * (y[0] + y[-1] + 4 * y[1:-1:2].sum() + 2 * y[2:-1:2].sum())


def phi(z):
    return np.exp(-0.5 * z * z) / math.sqrt(2 * math.pi)


def integral_abs(poly, roots):
    """The integral over the real line of |poly(z)| phi(z), by Simpson's rule between the
    sign changes of poly (where |poly| is smooth) and out to |z| = 12 (the tail is < 1e-30)."""
    cuts = sorted({-12.0, 12.0, *roots, *(-r for r in roots)})
    return sum(simpson(lambda z: np.abs(poly(z)) * phi(z), a, b) for a, b in zip(cuts, cuts[1:]))


def test_rigorous_constants_are_the_integrals_they_stand_for():
    z1, z2 = math.sqrt(2 - math.sqrt(3)), math.sqrt(2 + math.sqrt(3))
    k_w = integral_abs(lambda z: z**4 - 4 * z**2 + 1, [z1, z2])
    k_mu = integral_abs(lambda z: z**2 - 1, [1.0])
    # Simpson's error with 20000 panels per piece is far below 1e-11 here.
    assert bounds.rigorous_k_w() == pytest.approx(k_w, rel=1e-11)
    assert bounds.rigorous_k_mu() == pytest.approx(k_mu, rel=1e-11)
    assert bounds.rigorous_k_mu() == pytest.approx(4 * math.exp(-0.5) / math.sqrt(2 * math.pi), rel=1e-15)


def c_real_line(k, sigma):
    # c_R(sigma) = R M^2 / ((1 - g)^2 sigma^2) (max(|A| / (sqrt(2 pi) sigma), K_MU) + g / (2 (1 - g)))
    g = k.gamma
    box = k.action_volume / (math.sqrt(2 * math.pi) * sigma)
    k_mu = 4 * math.exp(-0.5) / math.sqrt(2 * math.pi)
    return k.r_max * k.m_phi**2 / ((1 - g) ** 2 * sigma**2) * (max(box, k_mu) + g / (2 * (1 - g)))


def test_rigorous_c_and_v_steps_match_the_closed_form():
    # The box term wins below sigma = |A| e^(1/2) / 4 = 1.2365 for |A| = 3, K_MU above.
    threshold = K.action_volume * math.exp(0.5) / 4
    for sigma in (0.3, 1.0, threshold * 1.01, 3.0):
        assert bounds.rigorous_c(K, sigma) == pytest.approx(c_real_line(K, sigma), rel=1e-13)
        if sigma < threshold:
            assert bounds.rigorous_c(K, sigma) == bounds.constants_c(K, sigma)
        else:
            assert bounds.rigorous_c(K, sigma) > bounds.constants_c(K, sigma)
    sigma, grad = 3.0, np.array([0.2, -0.6])
    c, n2 = c_real_line(K, sigma), 0.36
    assert bounds.rigorous_v_bound(K, sigma, grad, 1e-3) == pytest.approx(1e-3 * n2 - 1e-6 * c * n2, rel=1e-12)
    o = bounds.rigorous_v_safe_step(K, sigma, grad, 0.25 * n2 / (4 * c))
    vertex, lam = 1 / (2 * c), math.sqrt(1 - 0.25)
    assert o.kind == "feasible"
    assert o.vertex == pytest.approx(vertex, rel=1e-13) and o.c_max == pytest.approx(n2 / (4 * c), rel=1e-13)
    assert (o.lo, o.hi) == pytest.approx(((1 - lam) * vertex, (1 + lam) * vertex), rel=1e-12)


def d_closed_form(k, sigma):
    psi = 4 * (math.sqrt(7) - 2) * math.exp(math.sqrt(7) / 2 - 2) / math.sqrt(2 * math.pi)
    g = k.gamma
    return k.r_max / (1 - g) ** 2 * (psi * k.action_volume / (2 * sigma) + g / (1 - g))


def exploring_interval(g, eps, d, required):
    """{dw : dw g - |dw| eps - d dw^2 >= C}, by hand: on dw >= 0 the parabola
    dw (g - eps) - d dw^2, on dw <= 0 the parabola dw (g + eps) - d dw^2; each root by the
    quadratic formula."""
    def roots(a):
        disc = a * a - 4 * d * required
        return ((a - math.sqrt(disc)) / (2 * d), (a + math.sqrt(disc)) / (2 * d))

    lo = roots(g + eps)[0]  # the negative root of the left parabola (C < 0)
    hi = roots(g - eps)[1]  # the positive root of the right parabola
    return lo, hi


def test_the_exploring_bound_and_step_match_the_closed_form():
    sigma, g, eps, gl, required = 1.0, -0.3, 0.1, 0.4, -0.01
    d = d_closed_form(K, sigma)
    b = bounds.ExploringBound(K, sigma, g, eps)
    assert b.d == pytest.approx(d, rel=1e-13)
    for dw in (-0.01, 0.0, 0.02):
        assert b.value(dw) == pytest.approx(dw * g - abs(dw) * eps - d * dw * dw, rel=1e-13, abs=1e-300)
    a = abs(g) - eps
    assert b.vertex() == pytest.approx((-a / (2 * d), a * a / (4 * d)), rel=1e-13)
    lo, hi = exploring_interval(g, eps, d, required)
    s = b.safe_interval(required)
    assert s.kind == "feasible" and (s.lo, s.hi) == pytest.approx((lo, hi), rel=1e-12)
    # The step: beta = dw / grad_w_l_hat, the end furthest along grad_w_l_hat.
    step = bounds.exploring_w_exploring_step(K, sigma, g, eps, gl, required)
    assert step.chosen_step == pytest.approx(hi / gl, rel=1e-12)
    # Theorem 4.9 makes no update when grad_w_l_hat is within its width, the exploring step does.
    assert bounds.high_probability_w_safe_step_along_l(K, sigma, g, eps, gl, 0.5, required).kind == "below_noise"
    # With eps_J = 0 it is the interval of eq. (4.19).
    exact = bounds.exploring_w_exploring_step(K, sigma, g, 0.0, gl, required)
    thesis = bounds.w_update_safe_step_along_l(K, sigma, g, gl, required)
    assert (exact.lo, exact.hi) == pytest.approx((thesis.lo, thesis.hi), rel=1e-12)
    assert bounds.exploring_w_exploring_step(K, sigma, g, eps, 0.0, required).kind == "zero_gradient"


def c_decimal(k, sigma):
    """c(sigma) of Theorem 4.2 in 50-digit decimal arithmetic, from the exact values of the
    floats k and sigma."""
    g, r, m, a, s = (Decimal(x) for x in (k.gamma, k.r_max, k.m_phi, k.action_volume, sigma))
    one = Decimal(1)
    return r * m * m / ((one - g) ** 2 * s * s) * (a / ((2 * PI).sqrt() * s) + g / (2 * (one - g)))


def v_bound_decimal(k, sigma, grad, x):
    n2 = Decimal(max(abs(v) for v in grad)) ** 2
    x = Decimal(x)
    return x * n2 - x * x * c_decimal(k, sigma) * n2


def test_a_certified_v_step_meets_its_requirement_in_50_digit_arithmetic():
    sigma, grad = 0.7, [0.3, -0.8]
    cmax = bounds.v_update_c_max(K, sigma, grad)
    for required in (-0.01, 0.0, 0.5 * cmax, 0.999999 * cmax):
        o = bounds.certified_v_safe_step(K, sigma, grad, required)
        assert o.kind == "certified" and o.is_certified
        exact = v_bound_decimal(K, sigma, grad, o.chosen_step)
        assert exact >= Decimal(required)
        assert Decimal(o.bound.lo) <= exact <= Decimal(o.bound.hi)
        assert o.bound.lo >= required
        # The float interval's largest step, moved toward the vertex by ulps_moved ulps.
        assert o.interval.vertex <= o.chosen_step <= o.interval.hi
        assert (o.chosen_step == o.interval.hi) == (o.ulps_moved == 0)


def test_a_requirement_at_c_max_is_uncertifiable():
    sigma, grad = 1.0, [0.8]
    cmax = bounds.v_update_c_max(K, sigma, grad)
    o = bounds.certified_v_safe_step(K, sigma, grad, cmax)
    assert o.kind == "uncertifiable" and not o.is_certified
    assert o.chosen_step == pytest.approx(bounds.v_update_alpha_star(K, sigma), rel=1e-15)
    exact = v_bound_decimal(K, sigma, grad, o.chosen_step)
    assert Decimal(o.bound.lo) <= exact <= Decimal(o.bound.hi) and o.bound.lo < cmax
    assert bounds.certified_v_safe_step(K, sigma, grad, 1.01 * cmax).kind == "infeasible"
    assert bounds.certified_v_safe_step(K, sigma, [0.0], -1.0).kind == "zero_gradient"
    assert bounds.certified_v_safe_step(K, sigma, [0.0], -1.0).requirement_met is True
    assert bounds.certified_hp_v_safe_step(K, sigma, grad, 1.0, 0.0).kind == "below_noise"


def test_the_enclosures_contain_the_exact_values():
    sqrt_2pi = (2 * PI).sqrt()
    assert Decimal(bounds.certified_sqrt_2pi().lo) <= sqrt_2pi <= Decimal(bounds.certified_sqrt_2pi().hi)
    for sigma in (0.1, 0.7, 5.0):
        c = bounds.certified_c(K, sigma)
        assert Decimal(c.lo) <= c_decimal(K, sigma) <= Decimal(c.hi)
        assert c.width <= 1e-13 * c.hi
        assert bounds.certified_d(K, sigma).contains(bounds.constants_d(K, sigma))
    # psi = 4 (sqrt 7 - 2) exp(sqrt 7 / 2 - 2) / sqrt(2 pi), in 50 digits.
    r7 = Decimal(7).sqrt()
    psi = 4 * (r7 - 2) * (r7 / 2 - 2).exp() / sqrt_2pi
    assert Decimal(bounds.certified_psi().lo) <= psi <= Decimal(bounds.certified_psi().hi)


def test_interval_arithmetic_rounds_outward():
    third = bounds.Interval.point(0.1) / 3.0
    exact = Fraction(0.1) / 3
    assert Fraction(third.lo) <= exact <= Fraction(third.hi) and third.lo < third.hi
    r = bounds.Interval.point(2.0).sqrt()
    assert Fraction(r.lo) ** 2 <= 2 <= Fraction(r.hi) ** 2
    s = 1.0 + bounds.Interval(0.1, 0.2) * 3 - bounds.Interval.point(0.3)
    assert Fraction(s.lo) <= 1 + Fraction(0.1) * 3 - Fraction(0.3)
    assert 1 + Fraction(0.2) * 3 - Fraction(0.3) <= Fraction(s.hi)
    assert bounds.Interval(-1.0, 2.0).sqr().lo == 0.0
    assert (bounds.Interval.point(1.0) / bounds.Interval(-1.0, 1.0)).lo == -math.inf
    with pytest.raises(sepg.InvalidInputError):
        bounds.Interval(2.0, 1.0)
    with pytest.raises(sepg.InvalidInputError):
        bounds.Interval.point(math.nan)
    with pytest.raises(sepg.InvalidInputError):
        bounds.Interval.point(1.0) + "one"


def test_an_enclosure_certifies_the_float_outcome_of_its_bound():
    sigma, g, gl, required = 1.0, 0.3, -2.0, -0.1
    e = bounds.Enclosure.quadratic_w_along_l(K, sigma, g, gl)
    o = e.certify(bounds.w_update_safe_step_along_l(K, sigma, g, gl, required), required)
    direct = bounds.certified_w_safe_step_along_l(K, sigma, g, gl, required)
    # The direct wrapper may certify through the a-priori rounding-error bound, which moves a
    # failing step a few ulps further toward the vertex than the interval search does; both
    # steps must be certified by the same enclosure, and agree to within those ulps.
    assert o.kind == direct.kind == "certified"
    assert e.enclose(o.chosen_step).lo >= required
    assert e.enclose(direct.chosen_step).lo >= required
    assert abs(o.chosen_step - direct.chosen_step) <= 256 * math.ulp(o.chosen_step)
    # The bound of a step beta along grad_w_l: beta L J - beta^2 d L^2.
    d = d_closed_form(K, sigma)
    beta = o.chosen_step
    assert e.enclose(beta).contains(beta * gl * g - beta**2 * d * gl**2) or math.isclose(
        e.enclose(beta).lo, beta * gl * g - beta**2 * d * gl**2, rel_tol=1e-12
    )
    step, bound, ulps = e.certify_toward(o.interval.lo, o.interval.vertex, required)
    assert step is not None and bound.lo >= required and ulps >= 0
    x = bounds.Enclosure.exploring(K, sigma, -0.3, 0.1, 0.4)
    ex = x.certify(bounds.exploring_w_exploring_step(K, sigma, -0.3, 0.1, 0.4, -0.01), -0.01)
    assert ex == ex and ex.is_certified
    dx = bounds.certified_exploring_safe_step(K, sigma, -0.3, 0.1, 0.4, -0.01)
    assert x.enclose(dx.chosen_step).lo >= -0.01
    assert abs(ex.chosen_step - dx.chosen_step) <= 256 * math.ulp(ex.chosen_step)
    assert bounds.Enclosure.hp_v_update(K, sigma, [0.1], 0.2) is None
    r = bounds.Enclosure.rigorous(K, sigma, 0.5, 0.5)
    assert r.enclose(-0.2).contains(bounds.rigorous_bound(K, sigma, 0.5, -0.1)) or r.enclose(-0.2).lo <= bounds.rigorous_bound(K, sigma, 0.5, -0.1)


def inside(interval, exact):
    """Whether the interval contains the exact (Decimal) value."""
    return Decimal(interval.lo) <= exact <= Decimal(interval.hi)


def psi_decimal():
    r7 = Decimal(7).sqrt()
    return 4 * (r7 - 2) * (r7 / 2 - 2).exp() / (2 * PI).sqrt()


def d_decimal(k, sigma, psi=None):
    """d(sigma) of Theorem 4.3 (eq. 4.15) in 50-digit decimals, with Lemma A.1's psi unless
    ``psi`` is given."""
    g, r, a, s = (Decimal(x) for x in (k.gamma, k.r_max, k.action_volume, sigma))
    psi = psi_decimal() if psi is None else Decimal(psi)
    one = Decimal(1)
    return r / (one - g) ** 2 * (psi * a / (2 * s) + g / (one - g))


def test_a_quadratic_encloses_its_vertex_c_max_lambda_and_end_points():
    # B(x) = a x - b x^2 with the exact reals of the floats +-0.3 and 0.7, solved by hand in
    # 50-digit decimals: vertex a/(2b), C_max = a^2/(4b), lambda = sqrt(1 - C/C_max), and
    # the roots of B(x) = C, (a + s sqrt(a^2 - 4bC))/(2b) and its Vieta partner
    # 2C/(a + s sqrt(a^2 - 4bC)) (s = sign a; the form without cancellation, so that 50
    # digits give the small root to 50 digits too).
    for a_float in (0.3, -0.3):
        q = bounds.Quadratic(a_float, bounds.Interval.point(0.7))
        a, b = Decimal(a_float), Decimal(0.7)
        c_max = a * a / (4 * b)
        assert inside(q.c_max(), c_max) and inside(q.vertex(), a / (2 * b))
        assert inside(q.linear, a) and inside(q.quadratic, b)
        for required in (-0.05, 0.0, 0.01, 0.032):  # C_max = 0.03214...
            c = Decimal(required)
            assert inside(q.lambda_(required), (1 - c / c_max).sqrt())
            far = a + (1 if a > 0 else -1) * (a * a - 4 * b * c).sqrt()
            roots = sorted((far / (2 * b), 2 * c / far))
            lo, hi = q.end_points(required)
            assert inside(lo, roots[0]) and inside(hi, roots[1])
            for end in (lo, hi):
                assert end.width <= 1e-14 * max(abs(end.lo), abs(end.hi)) + 1e-300
        assert q.end_points(0.033) is None
        for x in (-1.0, 0.0, 0.25):
            assert inside(q.enclose(x), a * Decimal(x) - b * Decimal(x) ** 2)
    assert bounds.Quadratic(bounds.Interval(0.29, 0.31), 0.7).c_max().width > 1e-3


def test_the_quadratic_factories_hold_the_coefficients_of_theorems_4_2_to_4_5():
    sigma, gv, j, l = 0.7, [0.3, -0.8], 0.4, -1.2
    c, d = c_decimal(K, sigma), d_decimal(K, sigma)
    n2 = Decimal(-0.8) ** 2
    q = bounds.Quadratic.v_update(K, sigma, gv)
    assert inside(q.linear, n2) and inside(q.quadratic, c * n2)
    assert inside(q.c_max(), n2 / (4 * c)) and inside(q.vertex(), 1 / (2 * c))
    qj = bounds.Quadratic.w_along_j(K, sigma, j)
    assert inside(qj.linear, Decimal(j) ** 2) and inside(qj.quadratic, d * Decimal(j) ** 2)
    ql = bounds.Quadratic.w_along_l(K, sigma, j, l)
    assert inside(ql.linear, Decimal(j) * Decimal(l)) and inside(ql.quadratic, d * Decimal(l) ** 2)
    # The same bound as the Enclosure of the same theorem, and it certifies the float step.
    assert ql.enclose(-0.1) == bounds.Enclosure.quadratic_w_along_l(K, sigma, j, l).enclose(-0.1)
    o = ql.enclosure().certify(bounds.w_update_safe_step_along_l(K, sigma, j, l, -0.01), -0.01)
    assert o.kind == "certified" and ql.enclose(o.chosen_step).lo >= -0.01
    assert q == bounds.Quadratic.v_update(K, sigma, gv) and q != qj
    with pytest.raises(sepg.InvalidInputError, match="non-negative"):
        bounds.Quadratic(0.3, bounds.Interval(-0.1, 0.7))
    with pytest.raises(sepg.InvalidInputError):
        q.lambda_(math.nan)
    with pytest.raises(sepg.InvalidInputError):
        q.end_points(math.inf)
    with pytest.raises(sepg.InvalidInputError):
        bounds.Quadratic.w_along_j(K, 1.0, math.nan)


def test_the_entire_line_and_the_absolute_value():
    entire = bounds.Interval.ENTIRE
    assert (entire.lo, entire.hi) == (-math.inf, math.inf) and not entire.is_finite()
    assert entire == bounds.Interval(-math.inf, math.inf) and entire.contains(-1e308)
    # A divisor that contains 0 gives the whole line; it absorbs any operation.
    assert bounds.Interval.point(1.0) / bounds.Interval(-1.0, 1.0) == entire
    assert entire + 1.0 == entire and entire * 2.0 == entire
    assert abs(entire) == bounds.Interval(0.0, math.inf)
    assert abs(bounds.Interval(-3.0, 2.0)) == bounds.Interval(0.0, 3.0)
    assert bounds.Interval(-3.0, -2.0).abs() == bounds.Interval(2.0, 3.0)
    assert bounds.Interval(0.5, 2.0).abs() == bounds.Interval(0.5, 2.0)


def test_a_psi_override_replaces_lemma_a1_in_d():
    assert K.psi_override is None
    # Lemma A.1's psi as computed in floats: within a few ulps of the 50-digit value.
    assert abs(Decimal(K.psi_used) - psi_decimal()) <= 4 * Decimal(math.ulp(K.psi_used))
    k = K.with_psi(0.53)
    assert (k.psi_override, k.psi_used) == (0.53, 0.53) and k != K
    for sigma in (0.3, 2.0):
        assert bounds.constants_d(k, sigma) == pytest.approx(float(d_decimal(k, sigma, psi=0.53)), rel=1e-14)
        assert inside(bounds.certified_d(k, sigma), d_decimal(k, sigma, psi=0.53))
    assert bounds.constants_c(k, 1.0) == bounds.constants_c(K, 1.0)
    for bad in (0.0, -1.0, math.nan, math.inf):
        with pytest.raises(sepg.InvalidInputError):
            K.with_psi(bad)


def test_the_certified_adaptive_step_encloses_the_theorem_3_10_bound():
    # alpha* = |g|_2^2 / (2 c |g|_1^2) (Corollary 3.11); B(alpha) = alpha |g|_2^2 - alpha^2 c |g|_1^2.
    sigma, grad = 0.7, [0.3, -0.5]
    c = c_decimal(K, sigma)
    n2 = sum(Decimal(g) ** 2 for g in grad)
    n1 = sum(abs(Decimal(g)) for g in grad)
    o = bounds.certified_adaptive_step(K, sigma, grad)
    alpha = Decimal(o.chosen_step)
    # The guarantee is an interval evaluation, not the a-priori error bound of the fast path.
    assert o.kind == "certified" and o.ulps_moved == 0 and o.by_error_bound is False
    assert abs(alpha - n2 / (2 * c * n1 * n1)) <= Decimal("1e-15") * alpha
    assert inside(o.bound, alpha * n2 - alpha * alpha * c * n1 * n1) and o.bound.lo > 0
    zero = bounds.certified_adaptive_step(K, sigma, [0.0, 0.0])
    assert zero.kind == "zero_gradient" and zero.by_error_bound is None
    # An ordinary v-step (lqg1d's constants) is certified by the error bound of its float
    # evaluation; the same outcome certified through its enclosure is an interval search.
    lqg1d = sepg.TaskConstants(0.99, 28.8, 4.0, 8.0)
    fast = bounds.certified_v_safe_step(lqg1d, 0.5, [-3.7], 0.0)
    assert fast.kind == "certified" and fast.by_error_bound is True
    searched = bounds.Quadratic.v_update(lqg1d, 0.5, [-3.7]).enclosure().certify(
        bounds.v_update_safe_step(lqg1d, 0.5, [-3.7], 0.0), 0.0
    )
    assert searched.kind == "certified" and searched.by_error_bound is False


def test_a_step_outcome_contains_its_safe_interval_only():
    o = bounds.v_update_safe_step(K, 1.0, [0.5], 0.0)
    assert o.kind == "feasible"
    assert o.contains(o.lo) and o.contains(o.hi) and o.contains(o.vertex)
    assert not o.contains(o.hi * 1.01) and not o.contains(-1e-3)
    cmax = bounds.v_update_c_max(K, 1.0, [0.5])
    assert not bounds.v_update_safe_step(K, 1.0, [0.5], 2 * cmax).contains(0.0)


@pytest.mark.parametrize(
    "call",
    [
        lambda: bounds.certified_v_safe_step(K, math.nan, [0.5], 0.0),
        lambda: bounds.certified_v_safe_step(K, 1.0, [math.inf], 0.0),
        lambda: bounds.certified_hp_v_safe_step(K, 1.0, [0.5], 0.1, 0.0, form="other"),
        lambda: bounds.certified_exploring_safe_step(K, 1.0, 0.3, -0.1, 0.4, 0.0),
        lambda: bounds.certified_hp_w_safe_step_along_l(K, 1.0, (math.nan, 0.1), (0.4, 0.1), 0.0),
        lambda: bounds.ExploringBound(K, -1.0, 0.3, 0.1),
        lambda: bounds.rigorous_c(K, 0.0),
        lambda: bounds.Enclosure.quadratic_v_update(K, 1.0, []),
        lambda: bounds.Enclosure.quadratic_w_along_j(K, 1.0, 0.3).enclose(math.nan),
        lambda: bounds.Enclosure.quadratic_w_along_j(K, 1.0, 0.3).certify(
            bounds.w_update_safe_step_along_j(K, 1.0, 0.3, 0.0), math.inf
        ),
    ],
)
def test_bad_input_raises_one_typed_value_error(call):
    with pytest.raises(sepg.InvalidInputError):
        call()


@pytest.mark.skipif(not CLI.is_file(), reason="the sepg binary is built by `bash scripts/test.sh`")
def test_the_certified_steps_are_those_of_the_command_line():
    k, sigma, gv, gw, gl, req = sepg.TaskConstants(0.9, 2.0, 1.5, 3.0), 0.7, [0.3, -0.8], 0.4, -1.2, -0.01
    out = subprocess.run(
        [str(CLI), "bounds", "--gamma", "0.9", "--r-max", "2", "--m-phi", "1.5", "--action-volume", "3",
         "--sigma", "0.7", "--grad-v", "0.3,-0.8", "--grad-w", "0.4", "--grad-w-l", "-1.2",
         "--required", "-0.01", "--json", "--certified"],
        check=True, capture_output=True, text=True,
    ).stdout
    cli = json.loads(out)["certified"]
    enc = cli["enclosures"]
    for name, ours in (("psi", bounds.certified_psi()), ("c", bounds.certified_c(k, sigma)), ("d", bounds.certified_d(k, sigma))):
        assert [ours.lo, ours.hi] == enc[name]
    for name, ours in (
        ("alpha_bar", bounds.certified_v_safe_step(k, sigma, gv, req)),
        ("beta_bar_j", bounds.certified_w_safe_step_along_j(k, sigma, gw, req)),
        ("beta_bar", bounds.certified_w_safe_step_along_l(k, sigma, gw, gl, req)),
    ):
        step = cli["steps"][name]
        assert step["outcome"] == ours.kind == "certified" and ours.is_certified
        assert step["step"] == ours.chosen_step and step["bound"] == [ours.bound.lo, ours.bound.hi]
    # the Python report is the command line's object, built by the same library function
    report = _native.bounds_report(0.9, 2.0, 1.5, 3.0, 0.7, grad_v=gv, grad_w=gw, grad_w_l=gl,
                                   required=req, certified=True)
    assert report == json.loads(out)


def test_the_report_holds_the_closed_forms_and_labels_a_certified_step_as_its_certificate():
    # Theorem 4.2 at gamma = 1/2, R = M_phi = |A| = sigma = 1: c = 4 (1/sqrt(2 pi) + 1/2).
    r = bounds.bounds_report(0.5, 1.0, 1.0, 1.0, 1.0, grad_v=[0.3, -0.8], grad_w=0.4, required=-0.01,
                             certified=True)
    c = 4.0 * (1.0 / math.sqrt(2.0 * math.pi) + 0.5)
    assert r["c"] == pytest.approx(c, rel=1e-14)
    assert r["alpha_star"] == pytest.approx(1.0 / (2.0 * c), rel=1e-15)
    assert r["surrogate_coefficient"] == pytest.approx(1.0 / (4.0 * 2 * c), rel=1e-15)
    k = sepg.TaskConstants(0.5, 1.0, 1.0, 1.0)
    for name, ours in (
        ("alpha_bar", bounds.certified_v_safe_step(k, 1.0, [0.3, -0.8], -0.01)),
        ("beta_bar_j", bounds.certified_w_safe_step_along_j(k, 1.0, 0.4, -0.01)),
    ):
        assert r["certified"]["steps"][name]["outcome"] == ours.kind == "certified"
    assert "beta_bar" not in r["certified"]["steps"]
    tight = _native.bounds_report(0.9, 2.0, 1.5, 3.0, 0.7, constants="tight", horizon=20,
                                  rewards="non-positive")
    s_h = sum((t + 1) * 0.9**t for t in range(20))
    assert (tight["rho"], tight["horizon"]) == (0.5, "20")
    assert tight["s_h"] == pytest.approx(s_h, rel=1e-12)


@pytest.mark.parametrize(
    "kwargs",
    [dict(grad_w_l=0.3), dict(constants="other"), dict(rewards="two-sided"), dict(constants="tight"),
     dict(horizon=0, constants="tight"), dict(delta=0.2), dict(grad_v=[math.nan])],
)
def test_a_bad_report_query_raises_one_typed_value_error(kwargs):
    with pytest.raises(sepg.InvalidInputError):
        _native.bounds_report(0.9, 2.0, 1.5, 3.0, 0.7, **kwargs)
