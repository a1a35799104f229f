"""The action space of a study (docs/design.md §7): a grid over gait parameters, from the robot spec's
``[action_space]`` (bounds and grid step per :class:`~robustgait.gait.GaitParams` field).

An action is a grid index ``i ∈ {0, …, size − 1}`` (row-major over the axes, in the order of
:data:`robustgait.robots.spec.ACTION_FIELDS`). Learners work on the normalized grid: axis value
``v_j`` of an axis with ``n`` values maps to ``j / (n − 1) ∈ [0, 1]`` (an axis with one value maps to 0),
so a kernel lengthscale is a fraction of the axis range whatever its units.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from itertools import product

import numpy as np
from numpy.typing import NDArray

from robustgait.config import GaitParams
from robustgait.errors import RobustGaitError
from robustgait.robots import Robot
from robustgait.robots.spec import ACTION_FIELDS, ParamRange

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


@dataclass(frozen=True)
class ActionSpace:
    """A grid: ``names[k]`` takes the values ``values[k]`` (increasing)."""

    names: tuple[str, ...]
    values: tuple[tuple[float, ...], ...]

    def __post_init__(self) -> None:
        if not self.names or len(self.names) != len(self.values):
            raise RobustGaitError("an action space needs one tuple of values per parameter name")
        for name, vals in zip(self.names, self.values, strict=True):
            if not vals or any(not math.isfinite(v) for v in vals) or list(vals) != sorted(set(vals)):
                raise RobustGaitError(f"action space '{name}': values must be finite, distinct and increasing")

    @classmethod
    def from_ranges(cls, ranges: Mapping[str, ParamRange]) -> ActionSpace:
        names = tuple(k for k in ACTION_FIELDS if k in ranges) + tuple(k for k in ranges if k not in ACTION_FIELDS)
        return cls(names, tuple(ranges[k].grid() for k in names))

    @classmethod
    def from_robot(cls, robot: Robot, domains: str = "flat") -> ActionSpace:
        """The robot spec's ``[action_space]`` (``domains="flat"``) or its ``[action_space.multicontact]``
        sub-table (``domains="multicontact"``: multi-contact gaits need longer steps in time and may also
        search the rolling fraction); a spec without the table cannot be studied with that domain graph."""
        tables = {  # domain graph: (its ranges, what is missing when the spec has none)
            "flat": (robot.spec.action_space, "[action_space] table (bounds and grid step per gait parameter), "
                     "which studies search"),
            "multicontact": (robot.spec.multicontact_action_space, "[action_space.multicontact] table (bounds and "
                             "grid step per gait parameter of multi-contact gaits), which multi-contact studies "
                             "search"),
        }
        if domains not in tables:
            raise RobustGaitError(f"domains must be 'flat' or 'multicontact', got {domains!r}")
        ranges, missing = tables[domains]
        if ranges is None:
            raise RobustGaitError(f"{robot.spec.source or robot.name}: the robot spec has no {missing}")
        return cls.from_ranges(ranges)

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(v) for v in self.values)

    @property
    def dim(self) -> int:
        return len(self.names)

    @property
    def size(self) -> int:
        return math.prod(self.shape)

    def coords(self, index: int | IntArray) -> IntArray:
        """Per-axis value indices (…, d) of grid index/indices."""
        idx = np.asarray(index, dtype=np.int64)
        if np.any((idx < 0) | (idx >= self.size)):
            raise RobustGaitError(f"grid index out of range [0, {self.size})")
        return np.stack(np.unravel_index(idx, self.shape), axis=-1).astype(np.int64)

    def index_of_coords(self, coords: Sequence[int] | IntArray) -> int:
        return int(np.ravel_multi_index(tuple(np.asarray(coords, dtype=np.int64)), self.shape))

    def points(self) -> FloatArray:
        """Every grid point in physical units, (size, d), row i = action i."""
        return np.array(list(product(*self.values)), dtype=float).reshape(self.size, self.dim)

    def normalized(self, index: int | IntArray | None = None) -> FloatArray:
        """Normalized coordinates in [0, 1]^d of grid index/indices (all points when None), (…, d)."""
        c = self.coords(np.arange(self.size) if index is None else index)
        scale = np.array([max(n - 1, 1) for n in self.shape], dtype=float)
        return c / scale

    def normalize(self, values: Mapping[str, float]) -> FloatArray:
        """Normalized coordinates (d,) of any parameter values (on the grid or not): each axis' [first, last] value
        mapped onto [0, 1], as :meth:`normalized` maps the grid; an axis of one value maps to 0."""
        out = []
        for name, vals in zip(self.names, self.values, strict=True):
            if name not in values:
                raise RobustGaitError(f"missing parameter '{name}' of the action space")
            span = vals[-1] - vals[0]
            out.append((float(values[name]) - vals[0]) / span if span > 0 else 0.0)
        return np.asarray(out, dtype=float)

    def value(self, index: int) -> dict[str, float]:
        """Parameter name → value of action ``index``."""
        c = self.coords(index)
        return {n: self.values[k][int(c[k])] for k, n in enumerate(self.names)}

    def params(self, index: int) -> GaitParams:
        """The :class:`GaitParams` of action ``index`` (fields outside the space keep their defaults)."""
        try:
            return GaitParams(**self.value(index))
        except TypeError:
            raise RobustGaitError(f"action space names {self.names} are not GaitParams fields") from None

    def index(self, values: GaitParams | Mapping[str, float], *, tol: float = 1e-6) -> int:
        """Grid index of a parameter set; every value must be on the grid (within ``tol``)."""
        get = values.to_dict() if isinstance(values, GaitParams) else dict(values)
        coords = []
        for name, vals in zip(self.names, self.values, strict=True):
            if name not in get:
                raise RobustGaitError(f"missing parameter '{name}' of the action space")
            j = int(np.argmin(np.abs(np.asarray(vals) - get[name])))
            if abs(vals[j] - get[name]) > tol:
                raise RobustGaitError(f"{name} = {get[name]:g} is not on the action-space grid {vals}")
            coords.append(j)
        return self.index_of_coords(coords)

    def nearest(self, values: GaitParams | Mapping[str, float]) -> int:
        """Grid index of the grid point nearest a parameter set (on the grid or not): per axis the nearest value, a
        tie going to the lower one."""
        get = values.to_dict() if isinstance(values, GaitParams) else dict(values)
        missing = [n for n in self.names if n not in get]
        if missing:
            raise RobustGaitError(f"missing parameter '{missing[0]}' of the action space")
        # distances rounded to 1e-9 so that a tie in exact arithmetic is a tie here too (argmin: the first, lower)
        return self.index_of_coords([int(np.argmin(np.round(np.abs(np.asarray(vals) - get[name]), 9)))
                                     for name, vals in zip(self.names, self.values, strict=True)])

    def neighbours(self, index: int, radius: int = 1) -> IntArray:
        """Grid indices within ``radius`` grid steps of ``index`` along every axis (the box, including
        ``index`` itself), sorted."""
        c = self.coords(index)
        axes = [range(max(0, int(c[k]) - radius), min(n, int(c[k]) + radius + 1)) for k, n in enumerate(self.shape)]
        return np.sort(np.array([self.index_of_coords(x) for x in product(*axes)], dtype=np.int64))

    def describe(self) -> str:
        return " × ".join(f"{n} ({len(v)}: {v[0]:g}…{v[-1]:g})" for n, v in zip(self.names, self.values,
                                                                              strict=True))
