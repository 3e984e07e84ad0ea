"""SEPG and the comparison algorithms on gymnasium environments.

The policy is the factored linear Gaussian policy of the thesis (Sec 4.3.1, 4.3.4),
``a ~ N(V phi(s), diag(sigma^2))``, on features ``phi`` given by a Python callable (the
observation itself by default). Trajectories are collected here in Python, by stepping the
environment; the scores, the gradient estimates and their confidence widths (Sec 4.5), the
safe steps (Theorems 4.2-4.9) and the budget (Definition 4.3) are computed by the Rust
algorithms, the same code as the command line's runs.

Seeds follow gymnasium's conventions: trajectory ``i`` of a block starts with
``env.reset(seed=s_i)`` and draws its action noise from
``numpy.random.default_rng(p_i)``, where ``s_i`` and ``p_i`` derive from
``(seed, iteration, block, i)``. A run is therefore reproducible bit for bit, and a vector
environment gives the same records as a single one.

The bounds need the task constants: the discount ``gamma``, ``r_max`` (a bound on
``|r|``), ``m_phi`` (a bound on ``|phi_i(s)|``) and ``action_volume`` (the volume ``|A|`` of
the action space). A constant not given is derived from the spaces when it can be (``|A|``
from a bounded ``Box`` action space, ``M_phi`` from a bounded observation space with the
default identity features, ``R_max`` from a finite ``reward_range``), and the derivation is
shown; otherwise :class:`sepg.errors.MissingConstantError` says what to pass.
"""

import json
import math
import sys
import time
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from sepg._native import (
    _DEFAULT_ALGORITHM,
    _DEFAULT_BUDGET0,
    _DEFAULT_CONSTANTS,
    _DEFAULT_DELTA,
    _DEFAULT_N_TRAJECTORIES,
    _DEFAULT_NU,
    _DEFAULT_REQUIREMENT,
    _DEFAULT_SEED,
    BatchRequest,
    TaskConstants,
    Trainer,
)
from sepg.errors import InvalidInputError, MissingConstantError
from sepg import records_to_arrays, records_to_pandas
from sepg.callbacks import CallbackArg, as_callback
from sepg._progress import progress_bar as _progress_bar
from sepg.logger import Logger

Features = Callable[[np.ndarray], Any]


def _gymnasium() -> Any:
    try:
        import gymnasium
    except ImportError as e:  # pragma: no cover - exercised only without gymnasium
        raise InvalidInputError(
            "sepg.gym needs gymnasium: pip install gymnasium"
        ) from e
    return gymnasium


def _spaces(env: Any) -> Tuple[Any, Any, int]:
    """(action space, observation space, number of sub-environments) of an env or a vector
    env."""
    gymnasium = _gymnasium()
    if isinstance(env, gymnasium.vector.VectorEnv):
        return env.single_action_space, env.single_observation_space, int(env.num_envs)
    if isinstance(env, gymnasium.Env):
        return env.action_space, env.observation_space, 0
    raise InvalidInputError(
        f"env must be a gymnasium Env, a gymnasium VectorEnv or an environment id, got {type(env).__name__}"
    )


def _name(env: Any) -> str:
    spec = getattr(env, "spec", None)
    return spec.id if spec is not None and getattr(spec, "id", None) else type(env).__name__


def derive_constants(
    env: Any,
    *,
    gamma: float,
    r_max: Optional[float] = None,
    m_phi: Optional[float] = None,
    action_volume: Optional[float] = None,
    features: Optional[Features] = None,
) -> Tuple[TaskConstants, List[str]]:
    """The task constants of ``env`` and the derivation of those that were not given.

    ``|A|`` is the product of ``high - low`` of a bounded ``Box`` action space; ``M_phi`` is
    ``max(|low|, |high|)`` over a bounded ``Box`` observation space when the features are the
    observation itself (``features=None``); ``R_max`` is ``max(|lo|, |hi|)`` of a finite
    ``reward_range``. Raises :class:`MissingConstantError` naming every constant that is
    neither given nor derivable, and :class:`InvalidInputError` for a non-``Box`` action space.
    """
    gymnasium = _gymnasium()
    action_space, obs_space, _ = _spaces(env)
    if not isinstance(action_space, gymnasium.spaces.Box):
        raise InvalidInputError(
            f"SEPG's Gaussian policy needs a Box action space; {_name(env)} has {action_space}"
        )
    derivation: List[str] = []
    missing: List[str] = []
    name = _name(env)
    if action_volume is None:
        low = np.asarray(action_space.low, dtype=float)
        high = np.asarray(action_space.high, dtype=float)
        if np.all(np.isfinite(low)) and np.all(np.isfinite(high)):
            action_volume = float(np.prod(high - low))
            derivation.append(
                f"|A| = prod(high - low) = {action_volume:g} from the action space "
                f"Box(low={low.tolist()}, high={high.tolist()}) of {name}"
            )
        else:
            missing.append("action_volume (|A|: the action space is unbounded)")
    if m_phi is None:
        bounded_obs = isinstance(obs_space, gymnasium.spaces.Box) and np.all(
            np.isfinite(obs_space.low)
        ) and np.all(np.isfinite(obs_space.high))
        if features is None and bounded_obs:
            m_phi = float(
                max(np.max(np.abs(obs_space.low)), np.max(np.abs(obs_space.high)))
            )
            derivation.append(
                f"M_phi = max |bound| = {m_phi:g} of the observation space "
                f"Box(low={np.asarray(obs_space.low).tolist()}, high={np.asarray(obs_space.high).tolist()}), "
                "the features being the observation"
            )
        elif features is None:
            missing.append("m_phi (M_phi: the observation space is unbounded)")
        else:
            missing.append("m_phi (M_phi: a bound on |phi_i(s)| of the given features)")
    if r_max is None:
        reward_range = getattr(getattr(env, "unwrapped", env), "reward_range", None)
        if reward_range is not None and all(math.isfinite(x) for x in reward_range):
            r_max = float(max(abs(reward_range[0]), abs(reward_range[1])))
            derivation.append(
                f"R_max = max |reward_range| = {r_max:g} from reward_range {tuple(reward_range)} of {name}"
            )
        else:
            missing.append(f"r_max (R_max: {name} declares no finite reward range)")
    if missing:
        raise MissingConstantError(
            "the safety bounds need constants that cannot be derived from the spaces; pass "
            + "; ".join(missing)
        )
    return TaskConstants(gamma, r_max, m_phi, action_volume), derivation


class _Collector:
    """Collects the batches a :class:`sepg.Trainer` asks for by stepping a gymnasium env."""

    def __init__(self, env: Any, features: Features, horizon: int, actions: int, n_features: int):
        self.env = env
        self.features = features
        self.horizon = horizon
        self.actions = actions
        self.n_features = n_features
        self.steps = 0
        self.seconds = 0.0

    def phi(self, obs: Any) -> np.ndarray:
        phi = np.asarray(self.features(obs), dtype=float).reshape(-1)
        if phi.shape[0] != self.n_features:
            raise InvalidInputError(
                f"features returned {phi.shape[0]} values, earlier {self.n_features}"
            )
        if not np.all(np.isfinite(phi)):
            raise InvalidInputError(
                f"features must be finite: features({np.asarray(obs).tolist()}) = {phi.tolist()}"
            )
        return phi

    def __call__(self, req: BatchRequest) -> Tuple[np.ndarray, Optional[np.ndarray], Optional[np.ndarray], np.ndarray]:
        start = time.perf_counter()
        n, h, l, p = req.n, self.horizon, self.actions, self.n_features
        mean = req.mean
        sigma = None if req.sigma is None else np.asarray(req.sigma)
        rewards = np.zeros((n, h))
        actions = np.zeros((n, h, l)) if req.scores else None
        feats = np.zeros((n, h, p)) if req.scores else None
        lengths = np.zeros(n, dtype=np.int64)
        record = (rewards, actions, feats, lengths)
        k = getattr(self.env, "num_envs", None)
        if k is None:
            for i in range(n):
                self._single(req, i, mean, sigma, record)
        else:
            for first in range(0, n, int(k)):
                self._group(req, first, min(n, first + int(k)), mean, sigma, record)
        self.steps += int(lengths.sum())
        self.seconds += time.perf_counter() - start
        return record

    @staticmethod
    def _means(mean: np.ndarray, phi: np.ndarray) -> np.ndarray:
        """V phi(s) for one feature vector (shape (p,)) or a stack of them (shape (k, p)),
        with the same products and sums either way, so that a vector environment collects
        the trajectories of a single one bit for bit (a matrix product would not: BLAS
        kernels round differently for a vector and a matrix)."""
        return (mean * phi[..., None, :]).sum(axis=-1)

    def _single(self, req: BatchRequest, i: int, mean: np.ndarray, sigma: Optional[np.ndarray], record: Any) -> None:
        rewards, actions, feats, lengths = record
        obs, _ = self.env.reset(seed=int(req.env_seeds[i]))
        rng = np.random.default_rng(int(req.policy_seeds[i]))
        t = 0
        while t < self.horizon:
            phi = self.phi(obs)
            a = self._means(mean, phi)
            if sigma is not None:
                a = a + sigma * rng.standard_normal(self.actions)
            obs, r, terminated, truncated, _ = self.env.step(a)
            rewards[i, t] = float(r)
            if actions is not None:
                actions[i, t] = a
                feats[i, t] = phi
            t += 1
            if terminated or truncated:
                break
        lengths[i] = t

    def _group(self, req: BatchRequest, first: int, end: int, mean: np.ndarray, sigma: Optional[np.ndarray], record: Any) -> None:
        rewards, actions, feats, lengths = record
        k, m = int(self.env.num_envs), end - first
        seeds = [int(s) for s in req.env_seeds[first:end]] + [0] * (k - m)
        obs, _ = self.env.reset(seed=seeds)
        rngs = [np.random.default_rng(int(s)) for s in req.policy_seeds[first:end]]
        alive = np.zeros(k, dtype=bool)
        alive[:m] = True
        lengths[first:end] = self.horizon
        for t in range(self.horizon):
            phi = np.stack([self.phi(o) for o in obs])
            a = self._means(mean, phi)
            if sigma is not None:
                noise = np.zeros((k, self.actions))
                for j in range(m):
                    noise[j] = rngs[j].standard_normal(self.actions)
                a = a + sigma * noise
            obs, r, terminated, truncated, _ = self.env.step(a)
            for j in np.flatnonzero(alive):
                rewards[first + j, t] = float(r[j])
                if actions is not None:
                    actions[first + j, t] = a[j]
                    feats[first + j, t] = phi[j]
                if terminated[j] or truncated[j]:
                    alive[j] = False
                    lengths[first + j] = t + 1
            if not alive.any():
                break


class GymRun:
    """A run of SEPG (or a comparison algorithm) on a gymnasium environment.

    ``env`` is a gymnasium ``Env``, a ``VectorEnv`` (trajectories are collected
    ``num_envs`` at a time) or an environment id for ``gymnasium.make``. ``features`` maps an
    observation to the feature vector phi(s) (default: the observation itself). ``algorithm``
    is named as on the command line (``sepg-zv``, ``sepg-lv``, ``sepg-mi``, ``sepg-lb1``,
    ``sepg-lb2``, ``sepg-sim``, ``sepg-naive-w``, ``gpomdp-const``, ``gpomdp-adam``,
    ``adastep``); its hyper-parameters are ``nu``, ``requirement``, ``alpha``, ``beta``,
    ``lr`` and ``lr_w`` (as :class:`sepg.Trainer`'s); ``accounting`` (``"certified"``, the default: requirements
    built on the certified guarantees of the applied steps; ``"estimated"``: the thesis's
    bookkeeping) and ``reference_batch``, the N0 trajectories that estimate J(theta^0) before
    SEPG's first iteration under the estimated bookkeeping (default 1000; 0 takes it from the
    first v-block, as the thesis's pseudocode), and ``v_direction`` (``"greedy"``, the default, or
    ``"adam"`` with ``adam_lr`` and optionally ``adam_beta1``, ``adam_beta2``, ``adam_eps``: safe
    Adam, as :class:`sepg.Trainer`). ``horizon`` defaults to the environment's
    ``max_episode_steps``. ``constants`` is the family of the penalty coefficients c and d of
    every bound: ``"tight"`` (the default, as for ``sepg run``: c = rho R M_phi^2 S_H / sigma^2
    and d = 2 rho R S_H for the run's horizon, docs/THEOREMS.md "Tight constants") or
    ``"thesis"`` (Theorems 3.14, 4.2 and 4.3). A gymnasium environment states nothing about
    the sign of its rewards, so the tight constants are two-sided (rho = 1) unless
    ``rewards="non-positive"`` says that every reward lies in [-R_max, 0] (rho = 1/2).

    :meth:`run` runs iterations with optional callbacks (:mod:`sepg.callbacks`), a progress
    bar and a logger (:class:`sepg.logger.Logger`); ``records`` holds one dict per iteration
    with the columns of ``log.csv``.

    Every reward and feature vector collected is checked against R_max and M_phi
    (docs/RELIABILITY.md): ``on_contradiction="stop"`` (the default) raises
    :class:`sepg.RunFailedError` at the first value beyond its bound, naming the constant and
    the value; ``"continue"`` goes on and records the contradiction (no guarantee) in
    ``state["constants_check"]``.
    """

    def __init__(
        self,
        env: Any,
        features: Optional[Features] = None,
        *,
        gamma: float,
        algorithm: str = _DEFAULT_ALGORITHM,
        n_trajectories: int = _DEFAULT_N_TRAJECTORIES,
        horizon: Optional[int] = None,
        r_max: Optional[float] = None,
        m_phi: Optional[float] = None,
        action_volume: Optional[float] = None,
        seed: int = _DEFAULT_SEED,
        delta: float = _DEFAULT_DELTA,
        v0: Optional[Sequence[float]] = None,
        sigma0: Optional[Sequence[float]] = None,
        initial_budget: float = _DEFAULT_BUDGET0,
        show_derivation: bool = True,
        constants: str = _DEFAULT_CONSTANTS,
        rewards: Optional[str] = None,
        nu: float = _DEFAULT_NU,
        requirement: str = _DEFAULT_REQUIREMENT,
        alpha: Optional[float] = None,
        beta: Optional[float] = None,
        lr: Optional[float] = None,
        lr_w: Optional[float] = None,
        reference_batch: Optional[int] = None,
        accounting: Optional[str] = None,
        v_direction: Optional[str] = None,
        adam_lr: Optional[float] = None,
        adam_beta1: Optional[float] = None,
        adam_beta2: Optional[float] = None,
        adam_eps: Optional[float] = None,
        on_contradiction: Optional[str] = None,
    ) -> None:
        gymnasium = _gymnasium()
        if isinstance(env, str):
            env = gymnasium.make(env)
        self.env = env
        action_space, obs_space, _ = _spaces(env)
        self.constants, self.derivation = derive_constants(
            env,
            gamma=gamma,
            r_max=r_max,
            m_phi=m_phi,
            action_volume=action_volume,
            features=features,
        )
        if show_derivation:
            for line in self.derivation:
                print(f"sepg: {line}", file=sys.stderr)
        if features is None:
            features = lambda obs: np.asarray(obs, dtype=float).reshape(-1)  # noqa: E731
        if horizon is None:
            spec = getattr(env, "spec", None)
            horizon = getattr(spec, "max_episode_steps", None)
            if horizon is None:
                raise InvalidInputError(
                    f"{_name(env)} has no max_episode_steps: pass horizon"
                )
        if isinstance(horizon, bool) or not isinstance(horizon, (int, np.integer)) or horizon < 1:
            raise InvalidInputError(f"horizon must be a positive integer, got {horizon!r}")
        horizon = int(horizon)
        self.constants = self.constants.with_family(
            constants,
            horizon=horizon if constants == "tight" else None,
            rewards=rewards,
        )
        if not isinstance(action_space, gymnasium.spaces.Box) or len(action_space.shape) != 1:
            raise InvalidInputError(
                f"the action space must be a one-dimensional Box, got {action_space}"
            )
        self.actions = int(action_space.shape[0])
        probe = np.asarray(
            obs_space.sample() if not hasattr(obs_space, "low") else np.clip(0.0, obs_space.low, obs_space.high),
            dtype=float,
        )
        try:
            phi = np.asarray(features(probe), dtype=float).reshape(-1)
        except Exception as e:
            raise InvalidInputError(f"features failed on an observation: {e}") from e
        if phi.shape[0] == 0:
            raise InvalidInputError("features must return at least one value")
        self.n_features = int(phi.shape[0])
        self.algorithm = algorithm
        self.collector = _Collector(env, features, horizon, self.actions, self.n_features)
        self.trainer = Trainer(
            algorithm,
            self.constants,
            self.actions,
            self.n_features,
            self.collector,
            n_trajectories=n_trajectories,
            seed=seed,
            delta=delta,
            v0=v0,
            sigma0=sigma0,
            initial_budget=initial_budget,
            nu=nu,
            requirement=requirement,
            alpha=alpha,
            beta=beta,
            lr=lr,
            lr_w=lr_w,
            reference_batch=reference_batch,
            accounting=accounting,
            v_direction=v_direction,
            adam_lr=adam_lr,
            adam_beta1=adam_beta1,
            adam_beta2=adam_beta2,
            adam_eps=adam_eps,
            on_contradiction=on_contradiction,
        )
        self.records: List[Dict[str, Any]] = []

    def run(
        self,
        iterations: Optional[int] = None,
        *,
        total_timesteps: Optional[int] = None,
        callback: CallbackArg = None,
        progress_bar: Optional[bool] = None,
        logger: Optional[Logger] = None,
    ) -> Dict[str, np.ndarray]:
        """Runs ``iterations`` more iterations, or (``total_timesteps``) iterations until
        this call has used at least that many more environment steps (as stable-baselines3's
        ``learn``; the ``steps`` column counts the run's steps in all); returns every record
        so far as arrays (:func:`sepg.records_to_arrays`). An exception (of the environment,
        the features or a callback, or Ctrl-C) leaves the run after its last complete
        iteration, whose record is kept.

        ``callback`` is called once per iteration with the iteration's record (see
        :mod:`sepg.callbacks`); when it returns ``False`` the run stops after that
        iteration, which is complete and kept. ``progress_bar`` shows a tqdm bar on standard
        error (default: when standard error is a terminal). ``logger`` (a
        :class:`sepg.logger.Logger`) receives every record."""
        if (iterations is None) == (total_timesteps is None):
            raise InvalidInputError("pass either iterations or total_timesteps")
        goal = iterations if iterations is not None else total_timesteps
        name = "iterations" if iterations is not None else "total_timesteps"
        if isinstance(goal, bool) or not isinstance(goal, (int, np.integer)) or goal < 0:
            raise InvalidInputError(f"{name} must be a non-negative integer, got {goal!r}")
        goal = int(goal)
        hooks = as_callback(callback)
        by_steps = total_timesteps is not None
        start_steps = self._steps()
        bar = _progress_bar(
            progress_bar,
            total=goal,
            unit="step" if by_steps else "it",
            desc=f"{self.algorithm} on {_name(self.env)}",
        )
        if hooks is not None:
            hooks.on_training_start(self)
        done = 0
        try:
            while done < goal:
                record = self.trainer.run(1)[0]
                self.records.append(record)
                done = done + 1 if not by_steps else int(record["steps"]) - start_steps
                if logger is not None:
                    logger.record(record)
                if bar is not None:
                    bar.update(min(done, goal) - bar.n)
                    bar.set_postfix(j_explore=f"{record['j_explore']:.4g}", refresh=False)
                if hooks is not None and not hooks.on_step(record):
                    break
        finally:
            if bar is not None:
                bar.close()
            if hooks is not None:
                hooks.on_training_end()
        return records_to_arrays(self.records)

    def _steps(self) -> int:
        """Environment steps the run has used so far."""
        return int(self.state["steps"])

    @property
    def state(self) -> Dict[str, Any]:
        """The state after the last iteration: ``v`` (action-major), ``w``, ``budget``, ..."""
        return json.loads(self.trainer.state())

    @property
    def mean(self) -> np.ndarray:
        """The current mean matrix V, shape ``(actions, features)``."""
        return np.asarray(self.state["v"], dtype=float).reshape(self.actions, self.n_features)

    @property
    def sigma(self) -> np.ndarray:
        """The current standard deviations sigma = exp(w)."""
        return np.exp(np.asarray(self.state["w"], dtype=float))

    @property
    def steps_per_second(self) -> float:
        """Environment steps per second of wall-clock time spent collecting trajectories."""
        return self.collector.steps / self.collector.seconds if self.collector.seconds > 0 else 0.0

    def to_pandas(self) -> Any:
        """The records as a pandas DataFrame (needs pandas)."""
        return records_to_pandas(self.records)


def train(
    env: Any,
    features: Optional[Features] = None,
    *,
    iterations: int,
    gamma: float,
    algorithm: str = _DEFAULT_ALGORITHM,
    n_trajectories: int = _DEFAULT_N_TRAJECTORIES,
    horizon: Optional[int] = None,
    r_max: Optional[float] = None,
    m_phi: Optional[float] = None,
    action_volume: Optional[float] = None,
    seed: int = _DEFAULT_SEED,
    delta: float = _DEFAULT_DELTA,
    v0: Optional[Sequence[float]] = None,
    sigma0: Optional[Sequence[float]] = None,
    initial_budget: float = _DEFAULT_BUDGET0,
    show_derivation: bool = True,
    constants: str = _DEFAULT_CONSTANTS,
    rewards: Optional[str] = None,
    nu: float = _DEFAULT_NU,
    requirement: str = _DEFAULT_REQUIREMENT,
    alpha: Optional[float] = None,
    beta: Optional[float] = None,
    lr: Optional[float] = None,
    lr_w: Optional[float] = None,
    reference_batch: Optional[int] = None,
    accounting: Optional[str] = None,
    v_direction: Optional[str] = None,
    adam_lr: Optional[float] = None,
    adam_beta1: Optional[float] = None,
    adam_beta2: Optional[float] = None,
    adam_eps: Optional[float] = None,
    on_contradiction: Optional[str] = None,
    callback: CallbackArg = None,
    progress_bar: Optional[bool] = None,
    logger: Optional[Logger] = None,
) -> GymRun:
    """Builds a :class:`GymRun` (every argument but the last three is the constructor's) and
    runs ``iterations`` iterations with ``callback``, ``progress_bar`` and ``logger`` as
    :meth:`GymRun.run`; returns the run (its ``records``, ``mean``, ``sigma``,
    ``derivation``, ``steps_per_second``)."""
    run = GymRun(
        env,
        features,
        gamma=gamma,
        algorithm=algorithm,
        n_trajectories=n_trajectories,
        horizon=horizon,
        r_max=r_max,
        m_phi=m_phi,
        action_volume=action_volume,
        seed=seed,
        delta=delta,
        v0=v0,
        sigma0=sigma0,
        initial_budget=initial_budget,
        show_derivation=show_derivation,
        constants=constants,
        rewards=rewards,
        nu=nu,
        requirement=requirement,
        alpha=alpha,
        beta=beta,
        lr=lr,
        lr_w=lr_w,
        reference_batch=reference_batch,
        accounting=accounting,
        v_direction=v_direction,
        adam_lr=adam_lr,
        adam_beta1=adam_beta1,
        adam_beta2=adam_beta2,
        adam_eps=adam_eps,
        on_contradiction=on_contradiction,
    )
    run.run(iterations, callback=callback, progress_bar=progress_bar, logger=logger)
    return run


__all__ = ["GymRun", "derive_constants", "train"]
