"""Every quantity of the Rust crate ``sepg-bounds``.

Each function is named ``<module>_<function>`` after its Rust path, e.g.
``v_update::safe_step`` is :func:`v_update_safe_step`. The thesis reference of each is in its
docstring:

============================  ==========================================================
prefix                        thesis
============================  ==========================================================
``constants_``                psi (Lemma A.1), c (Theorems 3.14, 4.2), d (Theorem 4.3)
``pirotta_``                  Theorem 3.10, Corollary 3.11, Theorem 3.12
``papini_``                   Theorem 3.14
``batch_size_``               Corollary 3.13
``v_update_``                 Theorem 4.2, eqs. (4.8)-(4.10)
``w_update_``                 Theorems 4.3 and 4.5, eqs. (4.15)-(4.20)
``surrogate_``                Corollary 4.4, Appendix B
``high_probability_``         Theorems 4.7-4.9, eqs. (4.23)-(4.30)
``greedy_``                   Section 4.3.4
``rigorous_``                 Theorem 4.3 without neglected terms (Lemmas A.1-A.3), and
                              Theorem 4.2 with c sound on the real line (K_W, K_MU)
``exploring_``,               the exploring w-update: Theorem 4.3 on the confidence
:class:`ExploringBound`       event of grad_w J (Assumption 4.6)
``certified_``,               certified steps: Theorems 4.2-4.9, the rigorous and the
:class:`Interval`,            exploring bounds evaluated in outward-rounded interval
:class:`Quadratic`,           arithmetic; the outcome "uncertifiable" when C is within
:class:`Enclosure`,           rounding of C_max (docs/THEOREMS.md, "Certified steps");
:class:`Certified`            the adaptive step of Corollary 3.11 with its guarantee
``budget_``, :class:`Budget`  Definition 4.3, Theorem 4.1, eqs. (4.13)-(4.14)
:func:`bounds_report`         every quantity above at one point, as a dict: the report
                              of ``sepg bounds --json``, built by the same library code
============================  ==========================================================

Invalid input raises :class:`sepg.errors.InvalidInputError` (a ``ValueError``).
"""

from sepg._native import (
    Budget,
    Certified,
    Enclosure,
    ExploringBound,
    HighProbabilityBound,
    Interval,
    Quadratic,
    StepOutcome,
    TaskConstants,
    batch_size_gpomdp,
    bounds_report,
    batch_size_reinforce,
    budget_split_requirement,
    certified_adaptive_step,
    certified_c,
    certified_d,
    certified_exploring_safe_step,
    certified_hp_v_safe_step,
    certified_hp_w_safe_step_along_j,
    certified_hp_w_safe_step_along_l,
    certified_psi,
    certified_rigorous_safe_step_along_j,
    certified_rigorous_safe_step_along_l,
    certified_sqrt_2pi,
    certified_v_safe_step,
    certified_w_safe_step_along_j,
    certified_w_safe_step_along_l,
    constants_c,
    constants_d,
    constants_dc_dsigma,
    constants_psi,
    exploring_w_exploring_step,
    greedy_argmax_abs,
    greedy_coordinate_update,
    greedy_v_step,
    greedy_w_step,
    high_probability_corrected_norm,
    high_probability_v_safe_step,
    high_probability_w_safe_step_along_j,
    high_probability_w_safe_step_along_l,
    papini_bound,
    papini_greedy_step,
    pirotta_bound,
    pirotta_hp_bound,
    pirotta_hp_optimal_step,
    pirotta_optimal_step,
    rigorous_bound,
    rigorous_c,
    rigorous_gap,
    rigorous_k_mu,
    rigorous_k_w,
    rigorous_kl2,
    rigorous_safe_delta_w,
    rigorous_safe_step_along_j,
    rigorous_safe_step_along_l,
    rigorous_thesis_bound,
    rigorous_v_bound,
    rigorous_v_safe_step,
    surrogate_grad_sigma,
    surrogate_grad_w,
    surrogate_mixed_from_h,
    surrogate_surrogate,
    v_update_alpha_star,
    v_update_bound,
    v_update_c_max,
    v_update_safe_step,
    w_update_beta_star,
    w_update_beta_tilde,
    w_update_bound_along_j,
    w_update_bound_along_l,
    w_update_c_max,
    w_update_safe_step_along_j,
    w_update_safe_step_along_l,
)

__all__ = [
    "Budget",
    "Certified",
    "Enclosure",
    "ExploringBound",
    "HighProbabilityBound",
    "Interval",
    "Quadratic",
    "StepOutcome",
    "TaskConstants",
    "batch_size_gpomdp",
    "batch_size_reinforce",
    "bounds_report",
    "budget_split_requirement",
    "certified_adaptive_step",
    "certified_c",
    "certified_d",
    "certified_exploring_safe_step",
    "certified_hp_v_safe_step",
    "certified_hp_w_safe_step_along_j",
    "certified_hp_w_safe_step_along_l",
    "certified_psi",
    "certified_rigorous_safe_step_along_j",
    "certified_rigorous_safe_step_along_l",
    "certified_sqrt_2pi",
    "certified_v_safe_step",
    "certified_w_safe_step_along_j",
    "certified_w_safe_step_along_l",
    "constants_c",
    "constants_d",
    "constants_dc_dsigma",
    "constants_psi",
    "exploring_w_exploring_step",
    "greedy_argmax_abs",
    "greedy_coordinate_update",
    "greedy_v_step",
    "greedy_w_step",
    "high_probability_corrected_norm",
    "high_probability_v_safe_step",
    "high_probability_w_safe_step_along_j",
    "high_probability_w_safe_step_along_l",
    "papini_bound",
    "papini_greedy_step",
    "pirotta_bound",
    "pirotta_hp_bound",
    "pirotta_hp_optimal_step",
    "pirotta_optimal_step",
    "rigorous_bound",
    "rigorous_c",
    "rigorous_gap",
    "rigorous_k_mu",
    "rigorous_k_w",
    "rigorous_kl2",
    "rigorous_safe_delta_w",
    "rigorous_safe_step_along_j",
    "rigorous_safe_step_along_l",
    "rigorous_thesis_bound",
    "rigorous_v_bound",
    "rigorous_v_safe_step",
    "surrogate_grad_sigma",
    "surrogate_grad_w",
    "surrogate_mixed_from_h",
    "surrogate_surrogate",
    "v_update_alpha_star",
    "v_update_bound",
    "v_update_c_max",
    "v_update_safe_step",
    "w_update_beta_star",
    "w_update_beta_tilde",
    "w_update_bound_along_j",
    "w_update_bound_along_l",
    "w_update_c_max",
    "w_update_safe_step_along_j",
    "w_update_safe_step_along_l",
]
