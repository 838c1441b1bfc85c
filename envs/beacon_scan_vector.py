"""``SonarGym/BeaconScan-v0`` as a native vector env: N robots stepped in one process.

``gym.make_vec("SonarGym/BeaconScan-v0", num_envs=N, vectorization_mode="vector_entry_point")``
builds a :class:`BeaconScanVectorEnv`. It gives what ``vectorization_mode="sync"`` gives, to
the bit (observations, rewards, terminations, truncations and infos, autoresets included), at
less cost per step: it holds N unwrapped :class:`~sonar_gym.envs.beacon_scan.BeaconScanEnv`
and steps them itself, so there is no per-env wrapper stack (``PassiveEnvChecker``,
``OrderEnforcing``, ``TimeLimit``), no per-env info merging and no per-step batching of spaces.

What is batched: the actions (checked once for all robots), the observations (one preallocated
``(N, obs_dim)`` float32 array), rewards, terminations, truncations, and the infos (built as
arrays directly). What is not: each robot's physics, sonar pans and localization still run
robot by robot, in the same compiled kernels as the single env; each robot also keeps its own
room (a :class:`~sonar_gym.world.World` carries the episode's air temperature and the robot's
body, so robots cannot share one without changing what they sense).
"""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence
from typing import Any

import gymnasium as gym
import numpy as np
import numpy.typing as npt
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space

from sonar_gym.envs.beacon_scan import BeaconScanEnv
from sonar_gym.registration import REGISTRATIONS
from sonar_gym.validation import shown

__all__ = ["BeaconScanVectorEnv", "batch_infos"]

ENV_ID = "SonarGym/BeaconScan-v0"

InfoEntries = Sequence[tuple[int, Mapping[str, Any]]]
"""``(env index, info)`` pairs, in env order."""


class BeaconScanVectorEnv(gym.vector.VectorEnv[np.ndarray, np.ndarray, np.ndarray]):
    """N ``SonarGym/BeaconScan-v0`` robots stepped together (see the module docstring).

    Follows Gymnasium's ``VectorEnv`` contract with the ``NEXT_STEP`` autoreset mode, as
    ``SyncVectorEnv`` does: the step after a sub-env terminates or truncates resets it (no
    seed) and returns its reset observation and info, reward 0, not terminated, not truncated;
    the action given to it on that step is ignored. ``reset(seed=s)`` seeds sub-env ``i`` with
    ``s + i``; a list gives one seed (or None) per sub-env; ``options={"reset_mask": mask}``
    resets only the sub-envs where ``mask`` is True.

    Args:
        num_envs: the number of robots N, a whole number >= 1.
        max_episode_steps: the step limit ``gym.make`` applies to each env (its ``TimeLimit``):
            the step that reaches it is marked truncated. None: the registered limit
            (``gym.spec("SonarGym/BeaconScan-v0").max_episode_steps``), as with ``gym.make``.
        render_mode: ``"rgb_array"`` or None; ``render()`` gives one frame per robot.
        **kwargs: ``SonarGym/BeaconScan-v0``'s arguments, the same for every robot.

    Attributes:
        envs: the N unwrapped sub-envs (read their agent API, e.g. ``envs[0].encode_action``).
        single_observation_space: ``Box(-1, 1, (obs_dim,), float32)``, one robot's.
        observation_space: the same, batched: ``(N, obs_dim)``.
        single_action_space: one robot's (``MultiDiscrete([3, centres, widths, increments])``,
            or ``Discrete`` with ``action_type="discrete"``).
        action_space: batched: ``MultiDiscrete`` of shape ``(N, 4)``, or ``(N,)`` for discrete.

    Example:

    >>> import gymnasium as gym, sonar_gym
    >>> envs = gym.make_vec("SonarGym/BeaconScan-v0", num_envs=4,
    ...                     vectorization_mode="vector_entry_point")
    >>> observations, infos = envs.reset(seed=7)
    >>> observations.shape, envs.action_space.shape
    ((4, 159), (4, 4))
    >>> _ = envs.action_space.seed(7)
    >>> observations, rewards, terminated, truncated, infos = envs.step(envs.action_space.sample())
    >>> rewards.shape, sorted(infos)[:4]
    ((4,), ['_calibrated', '_estimated_pose', '_heading_error_rad', '_position_error_m'])
    >>> envs.close()
    """

    def __init__(
        self,
        num_envs: int = 1,
        max_episode_steps: int | None = None,
        render_mode: str | None = None,
        **kwargs: Any,
    ) -> None:
        super().__init__()
        self.num_envs = _check_count("num_envs", num_envs)
        if max_episode_steps is None:
            max_episode_steps = REGISTRATIONS[ENV_ID].max_episode_steps
        self.max_episode_steps: int = _check_count("max_episode_steps", max_episode_steps)
        self.envs = [BeaconScanEnv(render_mode=render_mode, **kwargs) for _ in range(num_envs)]
        first = self.envs[0]
        self.metadata = {**first.metadata, "autoreset_mode": AutoresetMode.NEXT_STEP}
        self.render_mode = first.render_mode
        self.single_observation_space = first.observation_space
        self.observation_space = batch_space(first.observation_space, num_envs)
        self.single_action_space = first.action_space
        self.action_space = batch_space(first.action_space, num_envs)
        self._action_low, self._action_high = _integer_bounds(self.action_space)
        self._multi_discrete = isinstance(first.action_space, gym.spaces.MultiDiscrete)

        observation_dim = int(np.prod(first.observation_space.shape))
        self._observations = np.zeros((num_envs, observation_dim), dtype=np.float32)
        self._rewards = np.zeros(num_envs, dtype=np.float64)
        self._terminations = np.zeros(num_envs, dtype=np.bool_)
        self._truncations = np.zeros(num_envs, dtype=np.bool_)
        self._autoreset_envs = np.zeros(num_envs, dtype=np.bool_)
        self._elapsed_steps = [0] * num_envs  # per robot, since its reset (the TimeLimit's)
        self._was_reset = [False] * num_envs

    # --- Gymnasium API ---------------------------------------------------------------
    def reset(
        self,
        *,
        seed: int | Sequence[int | None] | None = None,
        options: dict[str, Any] | None = None,
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset every robot (or those of ``options["reset_mask"]``); see the class docstring.

        Raises:
            ValueError: a list of seeds whose length is not ``num_envs``, or a bad reset mask.
            TypeError: a reset mask that is not a bool NumPy array.
        """
        seeds = self._seeds(seed)
        env_options = options
        indices: Sequence[int] = range(self.num_envs)
        if options is not None and "reset_mask" in options:
            mask = self._reset_mask(options["reset_mask"])
            env_options = {key: value for key, value in options.items() if key != "reset_mask"}
            indices = np.flatnonzero(mask).tolist()
            self._terminations[mask] = False
            self._truncations[mask] = False
            self._autoreset_envs[mask] = False
        else:
            self._terminations[:] = False
            self._truncations[:] = False
            self._autoreset_envs[:] = False
        entries: list[tuple[int, Mapping[str, Any]]] = []
        for index in indices:
            observation, info = self.envs[index].reset(seed=seeds[index], options=env_options)
            self._observations[index] = observation
            self._elapsed_steps[index] = 0
            self._was_reset[index] = True
            entries.append((index, info))
        return self._observations.copy(), self._infos(entries)

    def step(
        self, actions: npt.ArrayLike
    ) -> tuple[
        np.ndarray,
        npt.NDArray[np.float64],
        npt.NDArray[np.bool_],
        npt.NDArray[np.bool_],
        dict[str, Any],
    ]:
        """One step of every robot (an autoreset for those whose episode ended last step).

        Args:
            actions: an integer array of ``action_space``'s shape, ``(N, 4)`` (or ``(N,)``
                with ``action_type="discrete"``), each row in the single action space.

        Raises:
            ValueError: ``actions`` has the wrong shape or type, or a value out of range (the
                message says which and what is allowed).
            RuntimeError: ``reset`` has not been called.
        """
        if not all(self._was_reset):
            raise RuntimeError("BeaconScanVectorEnv: call reset() before step()")
        per_env = self._checked_actions(actions)
        limit = self.max_episode_steps
        entries: list[tuple[int, Mapping[str, Any]]] = []
        for index, env in enumerate(self.envs):
            if self._autoreset_envs[index]:
                observation, info = env.reset()
                self._elapsed_steps[index] = 0
                self._rewards[index] = 0.0
                self._terminations[index] = False
                self._truncations[index] = False
            else:
                observation, reward, terminated, truncated, info = env.step(per_env[index])
                self._elapsed_steps[index] += 1
                if self._elapsed_steps[index] >= limit:
                    truncated = True
                self._rewards[index] = reward
                self._terminations[index] = terminated
                self._truncations[index] = truncated
            self._observations[index] = observation
            entries.append((index, info))
        np.logical_or(self._terminations, self._truncations, out=self._autoreset_envs)
        return (
            self._observations.copy(),
            self._rewards.copy(),
            self._terminations.copy(),
            self._truncations.copy(),
            self._infos(entries),
        )

    def render(self) -> tuple[Any, ...]:
        """One frame per robot (each ``None`` unless ``render_mode="rgb_array"``)."""
        return tuple(env.render() for env in self.envs)

    def close_extras(self, **kwargs: Any) -> None:
        """Close every robot's env."""
        for env in self.envs:
            env.close()

    def call(self, name: str, *args: Any, **kwargs: Any) -> tuple[Any, ...]:
        """Call method ``name`` of every sub-env with the arguments (or read it, if it is not
        callable), as ``SyncVectorEnv.call`` does."""
        results = []
        for env in self.envs:
            attribute = getattr(env, name)
            results.append(attribute(*args, **kwargs) if callable(attribute) else attribute)
        return tuple(results)

    def get_attr(self, name: str) -> tuple[Any, ...]:
        """Attribute ``name`` of every sub-env."""
        return tuple(getattr(env, name) for env in self.envs)

    # --- helpers ---------------------------------------------------------------------
    def _seeds(self, seed: int | Sequence[int | None] | None) -> list[int | None]:
        """One seed per robot: ``seed + i``, each of a list, or None for all."""
        if seed is None:
            return [None] * self.num_envs
        if isinstance(seed, int):
            return [seed + index for index in range(self.num_envs)]
        seeds = list(seed)
        if len(seeds) != self.num_envs:
            raise ValueError(
                f"argument 'seed' must be an int, None, or a list of num_envs={self.num_envs} "
                f"seeds; got a list of {len(seeds)}: {shown(seed)}"
            )
        return seeds

    def _reset_mask(self, mask: Any) -> npt.NDArray[np.bool_]:
        """``options["reset_mask"]``, checked as ``SyncVectorEnv`` checks it."""
        if not isinstance(mask, np.ndarray):
            raise TypeError(
                f"options['reset_mask'] must be a numpy array, got {type(mask).__name__}"
            )
        if mask.shape != (self.num_envs,):
            raise ValueError(
                f"options['reset_mask'] must have shape ({self.num_envs},); got {mask.shape}"
            )
        if mask.dtype != np.bool_:
            raise TypeError(f"options['reset_mask'] must have dtype bool; got {mask.dtype}")
        if not mask.any():
            raise ValueError("options['reset_mask'] must hold at least one True value")
        return mask

    def _checked_actions(self, actions: npt.ArrayLike) -> list[Any]:
        """Each robot's action, after one check of the whole batch against ``action_space``."""
        array = np.asarray(actions)
        shape = self.action_space.shape
        if array.shape != shape or not np.issubdtype(array.dtype, np.integer):
            raise ValueError(
                f"argument 'actions' must be an integer array of shape {shape} (one action of "
                f"{self.single_action_space} per env); got {_described(array, actions)}"
            )
        outside = (array < self._action_low) | (array > self._action_high)
        if outside.any():
            rows = sorted(set(np.argwhere(outside)[:, 0].tolist()))
            raise ValueError(
                f"argument 'actions' must hold one action of {self.single_action_space} per env, "
                f"from {self._action_low[0].tolist()} to {self._action_high[0].tolist()}; "
                f"env(s) {rows} out of range in {shown(actions)}"
            )
        if self._multi_discrete:  # rows of the sub-envs' own dtype take their fast check
            return list(array.astype(self.single_action_space.dtype, copy=False))
        return [int(value) for value in array.tolist()]

    def _infos(self, entries: InfoEntries) -> dict[str, Any]:
        """The step's infos batched as ``SyncVectorEnv`` batches them (``_key`` masks)."""
        infos = batch_infos(entries, self.num_envs)
        if infos is not None:
            return infos
        merged: dict[str, Any] = {}  # infos of irregular shape: Gymnasium's own merge
        for index, info in entries:
            merged = self._add_info(merged, dict(info), index)
        return merged


def batch_infos(entries: InfoEntries, num_envs: int) -> dict[str, Any] | None:
    """The infos of ``entries`` as ``VectorEnv._add_info`` would merge them one by one.

    Per key, in order of first appearance: an array of ``num_envs`` values whose dtype comes
    from the first env that has the key (its Python or NumPy number type, an array's dtype
    and shape, else ``object``), zero (or None) for envs without it, and the bool mask
    ``_key`` of the envs that have it; nested dicts batch recursively.

    Returns:
        The batched infos, or None when a key holds a dict in some infos and not in others
        (the caller then merges with Gymnasium's own ``_add_info``).
    """
    indices = [index for index, _ in entries]
    infos = [info for _, info in entries]
    columns: dict[str, tuple[list[int], list[Any]]] = {}
    keys = infos[0].keys() if infos else None
    if keys is not None and all(info.keys() == keys for info in infos):  # the usual case
        for key in keys:
            columns[key] = (indices, [info[key] for info in infos])
    else:
        for index, info in entries:
            for key, value in info.items():
                if key not in columns:
                    columns[key] = ([], [])
                column_indices, column = columns[key]
                column_indices.append(index)
                column.append(value)
    batched: dict[str, Any] = {}
    for key, (column_indices, column) in columns.items():
        kinds = {type(value) for value in column}
        nested = [issubclass(kind, dict) for kind in kinds]
        if key != "final_obs" and any(nested):
            if not all(nested):
                return None
            inner = batch_infos(list(zip(column_indices, column, strict=True)), num_envs)
            if inner is None:
                return None
            batched[key] = inner
        else:
            batched[key] = _batched_column(key, column_indices, column, kinds, num_envs)
        batched[f"_{key}"] = _mask(column_indices, num_envs)
    return batched


def _batched_column(
    key: str, indices: list[int], column: list[Any], kinds: set[type], num_envs: int
) -> Any:
    """One key's values in an array made as ``_add_info`` makes it (from ``column[0]``), at
    ``indices``; ``kinds`` holds the types of the values."""
    first = column[0]
    kind = type(first)
    whole = len(kinds) == 1 and len(indices) == num_envs  # every env, values of one type
    if key != "final_obs" and (kind in (int, float, bool) or issubclass(kind, np.number)):
        if whole:
            return np.array(column, dtype=kind)
        array = np.zeros(num_envs, dtype=kind)
    elif key != "final_obs" and isinstance(first, np.ndarray):
        shape = (num_envs, *first.shape)
        if whole:
            stacked = _stacked(column)
            # one dtype for all means each value was cast to first.dtype, as assigning it would
            if stacked is not None and stacked.shape == shape and stacked.dtype == first.dtype:
                return stacked
        array = np.zeros(shape, dtype=first.dtype)
    else:
        if whole and kind is str:  # NumPy keeps strings whole in an object array
            return np.array(column, dtype=object)
        array = np.full(num_envs, fill_value=None, dtype=object)
    for index, value in zip(indices, column, strict=True):
        array[index] = value
    return array


def _stacked(arrays: list[np.ndarray]) -> np.ndarray | None:
    """``np.array(arrays)``, or None when their shapes differ."""
    try:
        return np.array(arrays)
    except ValueError:  # ragged
        return None


def _mask(indices: list[int], num_envs: int) -> npt.NDArray[np.bool_]:
    """True at ``indices``, False elsewhere (a new array)."""
    if len(indices) == num_envs:
        return _all_true(num_envs).copy()
    mask = np.zeros(num_envs, dtype=np.bool_)
    for index in indices:
        mask[index] = True
    return mask


@functools.cache
def _all_true(num_envs: int) -> npt.NDArray[np.bool_]:
    """``num_envs`` Trues, read-only (copied for each mask)."""
    mask = np.ones(num_envs, dtype=np.bool_)
    mask.setflags(write=False)
    return mask


def _integer_bounds(space: gym.Space[Any]) -> tuple[np.ndarray, np.ndarray]:
    """The lowest and highest value of each entry of a batched discrete action space (an
    integer ``Box`` batches ``MultiDiscrete`` spaces, a ``MultiDiscrete`` ``Discrete`` ones)."""
    if isinstance(space, gym.spaces.MultiDiscrete):
        return space.start, space.start + space.nvec - 1
    if isinstance(space, gym.spaces.Box) and np.issubdtype(space.dtype, np.integer):
        return space.low, space.high
    raise TypeError(f"expected a batched discrete action space; got {space}")


def _check_count(name: str, value: Any) -> int:
    """``value`` as a whole number >= 1; ``ValueError`` naming ``name`` if it is not."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        valid = False
    else:
        valid = bool(value >= 1)
    if not valid:
        raise ValueError(f"argument {name!r} must be a whole number >= 1; got {shown(value)}")
    return int(value)


def _described(array: np.ndarray, actions: Any) -> str:
    """What was given as actions: its shape and dtype, and the value itself."""
    return f"shape {array.shape}, dtype {array.dtype}: {shown(actions)}"
