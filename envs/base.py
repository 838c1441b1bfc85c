"""The small base every sonar_gym environment builds on.

A task subclasses :class:`SonarEnv` and fills four hooks: ``_reset_task`` (build the episode
from ``self.np_random``), ``_apply_action`` (one decision: sense, move or localize), ``_observe``
(the float32 observation) and ``_render_frame``. The base owns what must be the same
everywhere: seeding, action validation, the finite-value guard on observations and rewards,
the episode record, the wall-clock profile that ``sonar-gym benchmark`` reads, and three
opt-in services a task switches on when it is ready for them:

* reward terms: ``_apply_action`` returns ``StepOutcome(reward_terms={...})`` and the base sums
  them into the reward and copies them into ``info["rewards"]`` (HighwayEnv's ``_rewards``);
  every registered task gives its reward this way, under the names of :data:`REWARD_TERMS`;
* enforced info keys: a task that sets ``required_info_keys`` (every registered task sets
  :data:`INFO_KEYS`) gets an error as soon as a step's ``info`` lacks one;
* truncation: a task that sets ``max_decisions`` has its episodes truncated after that many
  steps (``info["status"]`` then reads ``"truncated"`` unless the task set it).

The agent API: scripted agents may read only what is declared here (the env's ``spec``,
``config``, ``observation_layout``, ``episode_count``, ``episode``) and a task's own documented
methods (``encode_action`` and the like), through :func:`unwrap_sonar_env`.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar

import gymnasium as gym
import numpy as np

from sonar_gym.phase_timer import PhaseTimer

if TYPE_CHECKING:  # listing agents imports this module, and must load no task code
    from sonar_gym.envs.action_types import ActionType
    from sonar_gym.envs.features import ObservationSpec

INFO_KEYS = ("position_error_m", "heading_error_rad", "sensing_time_s", "status")
"""The ``info`` keys every task reports on every step (opt in with ``required_info_keys``)."""
REWARDS_INFO_KEY = "rewards"
"""Where the base copies a step's reward terms in ``info``."""
REWARD_TERMS = {
    "sensing_cost": "minus the cost of this step's sensing time (``sensing_cost_per_s`` * s)",
    "pose_error": "minus the (capped) pose error of the estimate, in the task's error units",
    "failure": "minus ``failure_penalty`` when the method gives no pose or time runs out",
    "collision": "minus ``collision_penalty`` when the robot touched an obstacle",
    "path_loss": "BlockExpansion's episode loss: path error and failure parts in one number",
}
"""The names tasks give their reward terms, one per concept (a task uses those it has)."""


@dataclass
class StepOutcome:
    """What a task's ``_apply_action`` returns; the base adds the observation and checks.

    Give either ``reward`` or ``reward_terms`` (named parts of the reward, e.g.
    ``{"pose_error": -0.8, "sensing_cost": -0.1}``): with terms, the reward is their sum and
    ``info["rewards"]`` holds a copy of them.

    The sum runs in the terms' order, left to right, as a task would write it by hand
    (``a + b + c``, not a compensated sum), so a task that moves its arithmetic into terms
    keeps its rewards to the bit. Terms after the first that are exactly zero are skipped, so
    a task may report a fixed set of terms per step: a ``0.0`` placeholder cannot turn a
    ``-0.0`` reward into ``+0.0``.
    """

    reward: float = 0.0
    terminated: bool = False
    truncated: bool = False
    info: dict[str, Any] = field(default_factory=dict)
    reward_terms: Mapping[str, float] | None = None


@dataclass
class EpisodeRecord:
    """What the base counts over the current episode (read it as ``env.unwrapped.episode``).

    Attributes:
        index: episodes begun by ``reset`` so far, this one included (1 for the first).
        steps: steps taken in this episode.
        total_reward: sum of this episode's rewards.
        reward_terms: per-term sums of this episode's reward terms (tasks that give terms).
        done: the episode has terminated or been truncated.
    """

    index: int = 0
    steps: int = 0
    total_reward: float = 0.0
    reward_terms: dict[str, float] = field(default_factory=dict)
    done: bool = False


class SonarEnv(gym.Env[np.ndarray, Any], ABC):
    """Shared machinery of the sonar_gym tasks (not registered itself).

    Attributes:
        config: the task's frozen, validated configuration dataclass.
        observation_layout: the name of each observation feature group -> its slice of the
            observation vector.
        observation_spec: the features the observation is built from (``envs/features.py``).
        action_type: the action type the action space comes from (``envs/action_types.py``).
        required_info_keys: keys every step's ``info`` must hold (none unless a task opts in).
        unestimated_info_keys: required keys whose quantity the task does not estimate (for
            example a heading error where the method gives no heading): they read 0.0, never
            NaN, and summaries such as ``sonar-gym evaluate`` leave them out.
        max_decisions: steps after which the base truncates an episode (None: never).
    """

    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "render_fps": 4}
    observation_space: gym.spaces.Box  # every task observes a flat float32 vector
    required_info_keys: ClassVar[tuple[str, ...]] = ()
    unestimated_info_keys: ClassVar[tuple[str, ...]] = ()
    max_decisions: int | None = None
    config: Any
    observation_layout: dict[str, slice]
    observation_spec: ObservationSpec
    action_type: ActionType

    def __init__(self, render_mode: str | None = None) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"argument 'render_mode' must be one of {self.metadata['render_modes']} or None; "
                f"got {render_mode!r}"
            )
        self.render_mode = render_mode
        self.timing: dict[str, float] = {"sensing": 0.0, "localization": 0.0}
        self._episode_started = False
        self._record = EpisodeRecord()
        self._action_check: ActionCheck | None = None

    def _use_action_type(self, action_type: ActionType) -> None:
        """Present the task's choices as ``action_type`` (sets ``action_space`` from it)."""
        self.action_type = action_type
        self.action_space = action_type.space

    def _use_observation_spec(self, spec: ObservationSpec) -> None:
        """Build the observation from ``spec`` (sets ``observation_space`` and
        ``observation_layout`` from it)."""
        self.observation_spec = spec
        self.observation_layout = spec.observation_layout()
        self.observation_space = spec.space

    # --- the agent API -----------------------------------------------------------------
    @property
    def episode_count(self) -> int:
        """Episodes begun by ``reset`` so far; it changes exactly when a new episode starts, so
        an agent can tell a fresh episode from the next decision of the same one."""
        return self._record.index

    @property
    def episode(self) -> EpisodeRecord:
        """A copy of the current episode's record."""
        record = self._record
        return EpisodeRecord(
            record.index, record.steps, record.total_reward, dict(record.reward_terms), record.done
        )

    # --- hooks -------------------------------------------------------------------------
    @abstractmethod
    def _reset_task(self, options: dict[str, Any] | None) -> dict[str, Any]:
        """Build a new episode from ``self.np_random``; return the task's reset info."""

    @abstractmethod
    def _apply_action(self, action: Any) -> StepOutcome:
        """Carry out one validated action."""

    @abstractmethod
    def _observe(self) -> np.ndarray:
        """The current observation, an element of ``observation_space``."""

    @abstractmethod
    def _render_frame(self) -> np.ndarray:
        """An RGB image ``(H, W, 3)`` uint8 of the current state."""

    # --- Gymnasium API ---------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        info = self._reset_task(options)
        self._record = EpisodeRecord(index=self._record.index + 1)
        self._episode_started = True
        return self._checked_observation(), info

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        if not self._episode_started:
            raise RuntimeError(f"{type(self).__name__}: call reset() before step()")
        check = self._action_check
        if check is None or not check.is_current_for(self.action_space):
            check = self._action_check = ActionCheck(self.action_space)
        if not check(action):
            raise ValueError(
                f"{type(self).__name__}: action {action!r} is not in the action space "
                f"{self.action_space}"
            )
        outcome = self._apply_action(action)
        reward = self._reward_of(outcome)
        info = outcome.info
        record = self._record
        record.steps += 1
        record.total_reward += reward
        truncated = outcome.truncated
        if (
            self.max_decisions is not None
            and record.steps >= self.max_decisions
            and not outcome.terminated
        ):
            truncated = True
            info.setdefault("status", "truncated")
        missing = [key for key in self.required_info_keys if key not in info]
        if missing:
            raise RuntimeError(
                f"{type(self).__name__}: step info lacks the required key(s) {missing}; "
                f"it has {sorted(info)}"
            )
        if outcome.terminated or truncated:
            self._episode_started = False
            record.done = True
        return self._checked_observation(), reward, outcome.terminated, truncated, info

    def render(self) -> np.ndarray | None:
        if self.render_mode == "rgb_array":
            return self._render_frame()
        return None

    # --- helpers ---------------------------------------------------------------------
    def _reward_of(self, outcome: StepOutcome) -> float:
        """The step's reward: ``outcome.reward``, or the sum of its terms (copied into info)."""
        name = type(self).__name__
        if outcome.reward_terms is None:
            reward = float(outcome.reward)
            if not np.isfinite(reward):
                raise RuntimeError(f"{name}: non-finite reward {reward!r}")
            return reward
        if outcome.reward != 0.0:
            raise RuntimeError(
                f"{name}: a StepOutcome gives either reward or reward_terms; got reward "
                f"{outcome.reward!r} and terms {dict(outcome.reward_terms)}"
            )
        terms = {key: float(value) for key, value in outcome.reward_terms.items()}
        reward = _sum_in_order(list(terms.values()))
        finite = math.isfinite(reward)  # the sum of the terms is finite only if each term is
        if not finite:
            bad = {key: value for key, value in terms.items() if not math.isfinite(value)}
            if bad:
                raise RuntimeError(f"{name}: non-finite reward term(s) {bad}")
        sums = self._record.reward_terms
        for key, value in terms.items():
            sums[key] = sums.get(key, 0.0) + value
        outcome.info[REWARDS_INFO_KEY] = terms  # a fresh dict, not kept here
        if not finite:
            raise RuntimeError(f"{name}: reward terms {terms} overflow to {reward!r}")
        return reward

    def _checked_observation(self) -> np.ndarray:
        observation = self._observe()
        # A sum is finite unless an entry is not (or the sum overflows, which the full
        # check then clears). Python's sum of the entries as floats costs less than a NumPy
        # reduction over a short vector, and float32 entries cannot overflow it.
        if not math.isfinite(sum(observation.ravel().tolist())) and not (
            np.isfinite(observation).all()
        ):
            raise RuntimeError(f"{type(self).__name__}: non-finite observation")
        return observation

    def _timed(self, phase: str) -> PhaseTimer:
        """A context that adds the wall-clock time of its block to ``self.timing[phase]``
        (seconds)."""
        return PhaseTimer(self.timing, phase)


def _sum_in_order(values: list[float]) -> float:
    """``values[0] + values[1] + ...`` left to right, skipping zeros after the first (see
    :class:`StepOutcome`); 0.0 for no values."""
    if not values:
        return 0.0
    total = values[0]
    for value in values[1:]:
        if value != 0.0:
            total += value
    return total


class ActionCheck:
    """``space.contains`` with fast paths for ``MultiDiscrete`` and ``Discrete`` spaces.

    Gymnasium's ``contains`` goes through several NumPy calls and reductions, a noticeable
    share of a step. The common cases (an integer array of the space's own dtype and shape;
    a Python int or NumPy int64 for an int64 ``Discrete``) are answered with plain integer
    comparisons; every other value goes to ``space.contains``, so the check accepts and
    rejects exactly what ``space.contains`` does.

    The space's bounds, dtype and shape are read once, at construction; make a new check when
    the space's ``start``, ``nvec`` or ``n`` change (the env rebuilds it whenever
    ``action_space`` is replaced or these arrays are reassigned).
    """

    def __init__(self, space: gym.Space[Any]) -> None:
        self.space = space
        self._start: Any = None
        self._nvec: Any = None
        self._low: list[int] = []
        self._high: list[int] = []
        kind = type(space)
        self._dtype = space.dtype
        self._shape = space.shape
        self._multi_discrete = kind is gym.spaces.MultiDiscrete
        self._discrete = kind is gym.spaces.Discrete and space.dtype == np.int64
        if isinstance(space, gym.spaces.MultiDiscrete) and self._multi_discrete:
            self._start, self._nvec = space.start, space.nvec
            self._low = space.start.ravel().tolist()
            self._high = (space.start + (space.nvec - 1)).ravel().tolist()
        elif isinstance(space, gym.spaces.Discrete) and self._discrete:
            self._start, self._nvec = space.start, space.n
            self._low = [int(space.start)]
            self._high = [int(space.start) + int(space.n) - 1]

    def is_current_for(self, space: gym.Space[Any]) -> bool:
        """Whether this check was built for ``space`` as it is now (same bound arrays)."""
        if space is not self.space:
            return False
        if self._multi_discrete:
            return space.start is self._start and space.nvec is self._nvec  # type: ignore[attr-defined]
        if self._discrete:
            return space.start is self._start and space.n is self._nvec  # type: ignore[attr-defined]
        return True

    def __call__(self, action: Any) -> bool:
        """Whether ``action`` lies in the space; the same answer as ``space.contains``."""
        if self._multi_discrete:
            if (
                type(action) is np.ndarray
                and action.dtype == self._dtype
                and action.shape == self._shape
            ):
                # the same shape as the bounds: as many values as bounds
                for low, value, high in zip(
                    self._low, action.ravel().tolist(), self._high, strict=True
                ):
                    if not low <= value <= high:
                        return False
                return True
        elif self._discrete and (type(action) is int or type(action) is np.int64):
            return self._low[0] <= int(action) <= self._high[0]
        return bool(self.space.contains(action))


def unwrap_sonar_env(env: gym.Env[Any, Any]) -> SonarEnv:
    """The :class:`SonarEnv` under ``env``'s wrappers, the object agents read the API from.

    Raises:
        ValueError: ``env`` is not a sonar_gym environment (the message names what it is).
    """
    unwrapped = env.unwrapped
    if not isinstance(unwrapped, SonarEnv):
        raise ValueError(
            f"argument 'env' must be a sonar_gym environment (a SonarEnv under its wrappers); "
            f"got {type(unwrapped).__name__}"
            + (f" ({env.spec.id})" if env.spec is not None else "")
        )
    return unwrapped
