"""SEPG as a model object with the conventions of stable-baselines3: ``SEPG(env, ...)``,
``learn``, ``predict``, ``save`` and ``SEPG.load``.

The model wraps a :class:`sepg.gym.GymRun` (``model.run``): training is the same code, with
the same records, seeds and guarantees. A saved model is one JSON document (docs/PYTHON.md,
"Saved models"); loading it and continuing ``learn`` gives the records and parameters the
uninterrupted model would have had, bit for bit.
"""

from __future__ import annotations

import json
import os
from typing import Any, Dict, Optional, Sequence, Tuple, Union

import numpy as np

from sepg._native import (
    _DEFAULT_BUDGET0,
    _DEFAULT_CONSTANTS,
    _DEFAULT_DELTA,
    _DEFAULT_N_TRAJECTORIES,
    _DEFAULT_NU,
    _DEFAULT_REQUIREMENT,
    _DEFAULT_SEED,
    _REQUIREMENTS,
    __version__,
)
from sepg.callbacks import CallbackArg
from sepg.errors import InvalidInputError
from sepg.gym import Features, GymRun, _gymnasium
from sepg.logger import Logger

PathLike = Union[str, "os.PathLike[str]"]

#: The ``format`` field of a saved model.
FORMAT = "sepg-model"
#: The version of the saved-model format this code writes and reads.
FORMAT_VERSION = 1


class SEPG:
    """Safely-Exploring Policy Gradient (Algorithm 4.3) on a gymnasium environment, as a
    stable-baselines3-style model.

    ``requirement`` is the safety requirement of Table 4.1 (``"zv"``, the default, ``"lv"``,
    ``"mi"``, ``"lb1"``, ``"lb2"``, ``"sim"``); the other arguments are those of
    :class:`sepg.gym.GymRun` (``gamma`` is required; ``r_max``, ``m_phi`` and
    ``action_volume`` unless derivable from the spaces). ``seed`` seeds the trajectories and
    the generator of :meth:`predict`'s stochastic actions.
    """

    def __init__(
        self,
        env: Any,
        features: Optional[Features] = None,
        *,
        gamma: float,
        requirement: str = _DEFAULT_REQUIREMENT,
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
        constants: str = _DEFAULT_CONSTANTS,
        rewards: Optional[str] = None,
        nu: float = _DEFAULT_NU,
        reference_batch: Optional[int] = None,
        accounting: Optional[str] = None,
        v_direction: Optional[str] = None,
        adam_lr: Optional[float] = None,
        adam_beta1: Optional[float] = None,
        adam_beta2: Optional[float] = None,
        adam_eps: Optional[float] = None,
        show_derivation: bool = True,
        on_contradiction: Optional[str] = None,
    ) -> None:
        if requirement not in _REQUIREMENTS:
            raise InvalidInputError(
                f"unknown requirement {requirement!r}: expected one of {', '.join(_REQUIREMENTS)}"
            )
        self.requirement = requirement
        self.run = GymRun(
            env,
            features,
            gamma=gamma,
            algorithm=f"sepg-{requirement}",
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
            reference_batch=reference_batch,
            accounting=accounting,
            v_direction=v_direction,
            adam_lr=adam_lr,
            adam_beta1=adam_beta1,
            adam_beta2=adam_beta2,
            adam_eps=adam_eps,
            on_contradiction=on_contradiction,
        )
        k = self.run.constants
        # the resolved arguments: a saved model is rebuilt from these without deriving
        # anything again from the environment
        self._arguments: Dict[str, Any] = dict(
            gamma=k.gamma,
            requirement=requirement,
            n_trajectories=n_trajectories,
            horizon=self.run.collector.horizon,
            r_max=k.r_max,
            m_phi=k.m_phi,
            action_volume=k.action_volume,
            seed=seed,
            delta=delta,
            v0=None if v0 is None else np.asarray(v0, dtype=float).reshape(-1).tolist(),
            sigma0=None if sigma0 is None else np.asarray(sigma0, dtype=float).reshape(-1).tolist(),
            initial_budget=initial_budget,
            constants=constants,
            rewards=rewards,
            nu=nu,
            reference_batch=reference_batch,
            accounting=accounting,
            v_direction=v_direction,
            adam_lr=adam_lr,
            adam_beta1=adam_beta1,
            adam_beta2=adam_beta2,
            adam_eps=adam_eps,
            on_contradiction=on_contradiction,
        )
        self._custom_features = features is not None
        self._rng = np.random.default_rng(seed)
        self.logger: Optional[Logger] = None

    @property
    def env(self) -> Any:
        """The gymnasium environment."""
        return self.run.env

    @property
    def num_timesteps(self) -> int:
        """Environment steps used by training so far (the ``steps`` column)."""
        return int(self.run.state["steps"])

    @property
    def records(self) -> Any:
        """The records of the iterations run by this object (dicts with the columns of
        ``log.csv``)."""
        return self.run.records

    def set_logger(self, logger: Optional[Logger]) -> None:
        """Sends every later record to ``logger`` (a :class:`sepg.logger.Logger`; ``None``
        stops logging)."""
        self.logger = logger

    def learn(
        self,
        iterations: Optional[int] = None,
        *,
        total_timesteps: Optional[int] = None,
        callback: CallbackArg = None,
        progress_bar: Optional[bool] = None,
    ) -> "SEPG":
        """Trains for ``iterations`` more iterations, or until at least ``total_timesteps``
        more environment steps are used; ``callback`` and ``progress_bar`` as
        :meth:`sepg.gym.GymRun.run`. Returns the model."""
        self.run.run(
            iterations,
            total_timesteps=total_timesteps,
            callback=callback,
            progress_bar=progress_bar,
            logger=self.logger,
        )
        return self

    def predict(
        self,
        observation: Any,
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
    ) -> Tuple[np.ndarray, None]:
        """The action for ``observation`` (or one per row of a batch of observations) and
        ``None`` (the policy has no recurrent state; ``state`` and ``episode_start`` are
        accepted for stable-baselines3's signature and ignored). Deterministic: the mean
        V phi(s); otherwise V phi(s) + sigma z with z standard normal from the model's
        generator (seeded by ``seed``, saved with the model). The actions are not clipped to
        the action space, as in training (the environment clips them if it does)."""
        _, obs_space, _ = _spaces_of(self.run.env)
        obs = np.asarray(observation)
        shape = tuple(getattr(obs_space, "shape", None) or ())
        batch = shape != () and obs.ndim == len(shape) + 1
        rows = list(obs) if batch else [obs]
        collector = self.run.collector
        mean, sigma = self.run.mean, self.run.sigma
        actions = []
        for o in rows:
            a = collector._means(mean, collector.phi(o))
            if not deterministic:
                a = a + sigma * self._rng.standard_normal(self.run.actions)
            actions.append(a)
        return (np.stack(actions) if batch else actions[0]), None

    def save(self, path: PathLike) -> None:
        """Writes the model to ``path`` as one JSON document (docs/PYTHON.md, "Saved
        models"): the format, the sepg version, the environment id, the resolved
        arguments, the training state (the checkpoint of the Rust trainer) and the state of
        :meth:`predict`'s generator. The feature map, a Python callable, is not saved: a model
        trained with custom features is loaded with ``features=`` again."""
        spec = getattr(self.run.env, "spec", None)
        document = {
            "format": FORMAT,
            "format_version": FORMAT_VERSION,
            "sepg_version": __version__,
            "env_id": getattr(spec, "id", None),
            "features": "custom" if self._custom_features else "observation",
            "actions": self.run.actions,
            "n_features": self.run.n_features,
            "arguments": self._arguments,
            "state": json.loads(self.run.trainer.state()),
            "predict_rng": self._rng.bit_generator.state,
        }
        text = json.dumps(document, indent=1, allow_nan=False)
        with open(os.fspath(path), "w", encoding="utf-8") as f:
            f.write(text)
            f.write("\n")

    @classmethod
    def load(
        cls,
        path: PathLike,
        env: Any = None,
        *,
        features: Optional[Features] = None,
        show_derivation: bool = False,
    ) -> "SEPG":
        """The model saved at ``path``, on ``env`` (default: ``gymnasium.make`` of the saved
        environment id). ``features`` is required for a model trained with custom features
        and refused otherwise. Raises :class:`sepg.errors.InvalidInputError` for a file that
        is not a saved model of a format this version reads, or whose dimensions do not
        match ``env`` and ``features``."""
        with open(os.fspath(path), encoding="utf-8") as f:
            try:
                document = json.load(f)
            except json.JSONDecodeError as e:
                raise InvalidInputError(f"{os.fspath(path)} is not a saved model: {e}") from e
        if not isinstance(document, dict) or document.get("format") != FORMAT:
            raise InvalidInputError(f"{os.fspath(path)} is not a saved sepg model")
        if document.get("format_version") != FORMAT_VERSION:
            raise InvalidInputError(
                f"{os.fspath(path)} has format version {document.get('format_version')!r}; "
                f"this sepg reads version {FORMAT_VERSION}"
            )
        custom = document["features"] == "custom"
        if custom and features is None:
            raise InvalidInputError(
                "the model was trained with custom features: pass features= to load it"
            )
        if not custom and features is not None:
            raise InvalidInputError(
                "the model was trained on the observation itself: features= does not apply"
            )
        if env is None:
            if document.get("env_id") is None:
                raise InvalidInputError("the saved model names no environment id: pass env=")
            env = _gymnasium().make(document["env_id"])
        model = cls(env, features, show_derivation=show_derivation, **document["arguments"])
        if (model.run.actions, model.run.n_features) != (
            document["actions"],
            document["n_features"],
        ):
            raise InvalidInputError(
                f"the model has {document['actions']} actions and {document['n_features']} "
                f"features; env and features give {model.run.actions} and {model.run.n_features}"
            )
        model.run.trainer.set_state(json.dumps(document["state"]))
        model._rng.bit_generator.state = document["predict_rng"]
        return model


def _spaces_of(env: Any) -> Tuple[Any, Any, Any]:
    from sepg.gym import _spaces

    return _spaces(env)


__all__ = ["FORMAT", "FORMAT_VERSION", "SEPG"]
