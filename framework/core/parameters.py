"""Updating parameters: physical values, bounds and the normalized box [0, 1]^k.

Optimizers only ever see normalized coordinates

    x_i = (theta_i - lower_i) / (upper_i - lower_i),

tables report the physical value theta_i and the ratio theta_i / theta_i,0 to the
initial value.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from framework.core.errors import InputError


@dataclass(frozen=True)
class Parameter:
    """One uncertain model parameter.

    name: key passed to the model's build function; unit: SI unit string ("N/m", "m",
    "-" for ratios); initial: value of the initial (a priori) model; lower/upper: bounds.
    """

    name: str
    initial: float
    lower: float
    upper: float
    unit: str = "-"
    description: str = ""

    def __post_init__(self) -> None:
        where = f"parameter {self.name!r}"
        for field in ("initial", "lower", "upper"):
            value = getattr(self, field)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
                raise InputError(f"{where}: {field} must be a number, got {value!r}")
            if not math.isfinite(float(value)):
                raise InputError(f"{where}: {field} must be finite, got {value!r}")
        if not self.name or not isinstance(self.name, str):
            raise InputError(f"parameter name must be a non-empty string, got {self.name!r}")
        if self.lower > self.upper:
            raise InputError(f"{where}: bounds are swapped (lower={self.lower!r} > upper={self.upper!r})")
        if self.lower == self.upper:
            raise InputError(f"{where}: bounds are empty (lower == upper == {self.lower!r})")
        if not (self.lower <= self.initial <= self.upper):
            raise InputError(
                f"{where}: initial={self.initial!r} is outside bounds [{self.lower!r}, {self.upper!r}]"
            )

    @property
    def span(self) -> float:
        return float(self.upper - self.lower)


class ParameterSet(Sequence[Parameter]):
    """An ordered, immutable set of parameters with the normalization maps."""

    def __init__(self, parameters: Iterable[Parameter]):
        self._items: tuple[Parameter, ...] = tuple(parameters)
        if not self._items:
            raise InputError("parameters: at least one updating parameter is required")
        names = [p.name for p in self._items]
        duplicates = sorted({n for n in names if names.count(n) > 1})
        if duplicates:
            raise InputError(f"parameters: duplicate names {duplicates}")
        self.lower = np.array([p.lower for p in self._items], dtype=float)
        self.upper = np.array([p.upper for p in self._items], dtype=float)
        self.initial = np.array([p.initial for p in self._items], dtype=float)

    def __getitem__(self, index):  # type: ignore[override]
        return self._items[index]

    def __len__(self) -> int:
        return len(self._items)

    def __repr__(self) -> str:
        return f"ParameterSet({[p.name for p in self._items]})"

    def __eq__(self, other: object) -> bool:
        return isinstance(other, ParameterSet) and self._items == other._items

    def __hash__(self) -> int:
        return hash(self._items)

    @property
    def names(self) -> list[str]:
        return [p.name for p in self._items]

    @property
    def units(self) -> list[str]:
        return [p.unit for p in self._items]

    def by_name(self, name: str) -> Parameter:
        for p in self._items:
            if p.name == name:
                return p
        raise KeyError(f"no parameter named {name!r}; known: {self.names}")

    def subset(self, names: Iterable[str]) -> ParameterSet:
        names = list(names)
        unknown = [n for n in names if n not in self.names]
        if unknown:
            raise InputError(f"parameters.names: no parameter named {unknown[0]!r}; known: {self.names}")
        return ParameterSet(self.by_name(n) for n in names)

    # --- maps between normalized x, physical theta and ratios -----------------------
    def to_physical(self, x: np.ndarray) -> np.ndarray:
        """theta = lower + x (upper - lower); x of shape (k,) or (n, k)."""
        return self.lower + np.asarray(x, dtype=float) * (self.upper - self.lower)

    def to_normalized(self, theta: np.ndarray) -> np.ndarray:
        """x = (theta - lower) / (upper - lower)."""
        return (np.asarray(theta, dtype=float) - self.lower) / (self.upper - self.lower)

    def to_ratio(self, theta: np.ndarray) -> np.ndarray:
        """theta / theta_0 (NaN where the initial value is 0)."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(self.initial != 0, np.asarray(theta, float) / self.initial, np.nan)

    @property
    def x_initial(self) -> np.ndarray:
        return self.to_normalized(self.initial)

    def as_dict(self, theta: np.ndarray) -> dict[str, float]:
        """Map a physical vector to {name: value}, the form build functions receive."""
        theta = np.asarray(theta, dtype=float)
        if theta.shape != (len(self),):
            raise InputError(
                f"parameter vector has shape {theta.shape}, expected ({len(self)},) for {self.names}"
            )
        return {p.name: float(v) for p, v in zip(self._items, theta)}

    def from_dict(self, values: Mapping[str, float]) -> np.ndarray:
        missing = [n for n in self.names if n not in values]
        if missing:
            raise InputError(f"parameter values missing for {missing}")
        return np.array([float(values[n]) for n in self.names])

    def with_bounds(self, bounds: Mapping[str, tuple[float, float]]) -> ParameterSet:
        """Copy with some bounds replaced (names must exist)."""
        out = []
        for p in self._items:
            if p.name in bounds:
                lo, hi = bounds[p.name]
                p = Parameter(p.name, p.initial, float(lo), float(hi), p.unit, p.description)
            out.append(p)
        unknown = sorted(set(bounds) - set(self.names))
        if unknown:
            raise InputError(f"bounds given for unknown parameters {unknown}; known: {self.names}")
        return ParameterSet(out)
