"""Dispersions: what varies from run to run of a campaign, and how.

A dispersion is ``Instance.variable=DIST`` (``--vary``, or one entry of a TOML/JSON file).
``variable`` is a scalar FMI name (``inertia[2,3]``) or a whole array variable.

Random (Monte Carlo) — drawn anew for every run:
  ``normal(mean, sd)``, ``uniform(lo, hi)``, ``choice(a, b, ...)``, ``integers(lo, hi)``
  (a whole number uniform in [lo, hi]: a noise ``seed``, so that every run draws its own
  noise, ``StarTracker.seed=integers(0, 2147483647)``); on a whole array each
  element is drawn independently from the same distribution.  ``choice`` and ``values``
  take the names of a named-choice parameter too (``CmgSteering.law=choice(PSEUDO_INVERSE,
  SR_INVERSE)``); the table records the name, as ``--set`` takes it.
  ``rotate(sd)``: each unit vector (a 3-vector, or each row of an n×3 matrix such as
  ``CmgCluster.gimbal_axis``) is turned by a small rotation φ = sd (n₁ e₁ + n₂ e₂),
  n ~ N(0, 1), e₁, e₂ ⊥ the vector (Rodrigues), so it stays a unit vector and the tilt has
  the standard deviation sd about each perpendicular axis.
  ``inertia(sd_rel, sd_angle)``: a 3×3 inertia J = R diag(λ) Rᵀ gets principal moments
  λᵢ (1 + sd_rel nᵢ) and principal axes turned by a rotation vector of standard deviation
  sd_angle per axis; it stays symmetric positive definite.  Draws whose moments break the
  triangle inequality λᵢ ≤ λⱼ + λₖ (no rigid body has them) are redrawn (a truncated
  distribution, negligible at the few-percent sds in use).
Grids (sweeps) — several give the full factorial, combined with the random draws:
  ``linspace(lo, hi, n)``, ``values(a, b, ...)`` (scalars only).

A leading ``+`` adds the draw to the system's nominal value, a leading ``*`` multiplies it
(``CmgCluster.delta0=+normal(0, 0.5deg)``, ``CmgCluster.h_rotor=*normal(1, 0.01)``).
Numbers are SI; ``deg`` after a number converts it to rad.

Reproducibility: the draws of run i for a dispersion come from
``SeedSequence(seed, spawn_key=(i, crc32(key)))`` alone, so they do not depend on the
number of workers, on the order of completion, on the other dispersions or on N.
"""

from __future__ import annotations

import json
import math
import re
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

#: the most runs a campaign may have (grid points × runs per point): its journal and table
#: are held in memory, at about a kilobyte a run (a larger study: several campaigns)
MAX_RUNS = 100_000
RANDOM = {"normal": 2, "uniform": 2, "choice": None, "rotate": 1, "inertia": 2, "integers": 2}
GRIDS = {"linspace": 3, "values": None}
_EXPR = re.compile(r"^\s*([+*]?)\s*([a-z_]+)\s*\((.*)\)\s*$", re.S)
_NUMBER = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(deg)?\s*$")
_NAME = re.compile(r"^\s*([A-Za-z_]\w*)\s*$")  # a named choice (CmgSteering.law)
_KEY = re.compile(r"^[A-Za-z_]\w*\.[A-Za-z_]\w*(\[\d+(,\d+)*\])?$")


@dataclass(frozen=True)
class Dispersion:
    key: str  # "Instance.variable" or "Instance.variable[i,j]"
    kind: str  # one of RANDOM or GRIDS
    args: tuple  # floats; for choice and values also names, until the plan resolves them
    mode: str = ""  # "" replace, "+" add to nominal, "*" multiply nominal
    text: str = ""  # as written

    @property
    def is_grid(self) -> bool:
        return self.kind in GRIDS

    @property
    def instance(self) -> str:
        return self.key.partition(".")[0]

    @property
    def variable(self) -> str:
        return self.key.partition(".")[2].partition("[")[0]

    @property
    def points(self) -> int:
        """The number of values of a grid (without making them)."""
        return int(self.args[2]) if self.kind == "linspace" else len(self.args)

    def grid(self) -> list[float]:
        if self.kind == "linspace":
            lo, hi, n = self.args
            return np.linspace(lo, hi, int(n)).tolist()
        return list(self.args)

    def apply(self, value, nominal: np.ndarray) -> np.ndarray:
        value = np.asarray(value, dtype=float)
        if self.mode == "+":
            return nominal + value
        if self.mode == "*":
            return nominal * value
        return np.broadcast_to(value, nominal.shape).astype(float)

    def draw(self, seed: int, index: int, nominal: np.ndarray) -> np.ndarray:
        """This dispersion's value for run ``index`` (same shape as ``nominal``)."""
        rng = np.random.default_rng(
            np.random.SeedSequence(seed, spawn_key=(index, zlib.crc32(self.key.encode())))
        )
        shape = nominal.shape
        if self.kind == "normal":
            return self.apply(rng.normal(self.args[0], self.args[1], shape), nominal)
        if self.kind == "uniform":
            return self.apply(rng.uniform(self.args[0], self.args[1], shape), nominal)
        if self.kind == "choice":
            return self.apply(rng.choice(np.asarray(self.args), shape), nominal)
        if self.kind == "integers":
            low, high = (int(a) for a in self.args)
            return self.apply(rng.integers(low, high, shape, endpoint=True), nominal)
        if self.kind == "rotate":
            return rotate_rows(nominal, self.args[0], rng)
        if self.kind == "inertia":
            return disperse_inertia(nominal, self.args[0], self.args[1], rng)
        raise AssertionError(self.kind)


def parse(text: str, origin: str = "--vary") -> Dispersion:
    """``"A.x=+normal(0, 0.5deg)"`` -> :class:`Dispersion`; errors name ``origin``."""
    key, sep, expression = text.partition("=")
    key = key.strip().replace(" ", "")
    if not sep or not _KEY.match(key):
        raise ValueError(
            f"{origin} {text!r}: expected Instance.variable=DIST, e.g. "
            "SatelliteDynamics.inertia[1,1]=normal(956, 10)"
        )
    return expression_to_dispersion(key, expression, origin)


def expression_to_dispersion(key: str, expression: str, origin: str) -> Dispersion:
    match = _EXPR.match(expression)
    if not match:
        raise ValueError(
            f"{origin} {key}={expression}: expected DIST(args), DIST one of "
            f"{', '.join([*RANDOM, *GRIDS])}, optionally after + or *"
        )
    mode, kind, body = match.groups()
    if kind not in RANDOM and kind not in GRIDS:
        raise ValueError(
            f"{origin} {key}: unknown distribution {kind!r}; known: {', '.join([*RANDOM, *GRIDS])}"
        )
    args = []
    for item in body.split(","):
        number = _NUMBER.match(item)
        if not number and kind in ("choice", "values") and _NAME.match(item):
            args.append(item.strip())
            continue
        if not number:
            raise ValueError(
                f"{origin} {key}={expression}: {item.strip()!r} is not a number "
                "(SI, or degrees with a 'deg' suffix)"
            )
        args.append(float(number.group(1)) * (math.pi / 180 if number.group(2) else 1.0))
    infinite = [a for a in args if isinstance(a, float) and not math.isfinite(a)]
    if infinite:
        raise ValueError(
            f"{origin} {key}={expression.strip()}: the parameters of {kind} must be finite "
            f"numbers, got {infinite[0]!r}"
        )
    wanted = {**RANDOM, **GRIDS}[kind]
    if wanted is not None and len(args) != wanted or not args:
        raise ValueError(
            f"{origin} {key}: {kind} takes {wanted or 'one or more'} argument(s), got {len(args)}"
        )
    if kind in ("normal", "rotate") and args[-1] < 0 or kind == "inertia" and min(args) < 0:
        raise ValueError(f"{origin} {key}: a standard deviation must be ≥ 0, got {args}")
    if kind in ("uniform", "integers") and args[0] > args[1]:
        raise ValueError(f"{origin} {key}: {kind}(lo, hi) needs lo <= hi, got {args}")
    if kind == "integers" and any(a != int(a) for a in args):
        raise ValueError(f"{origin} {key}: integers(lo, hi) takes whole numbers, got {args}")
    if kind == "linspace" and (args[2] < 1 or args[2] != int(args[2])):
        raise ValueError(f"{origin} {key}: linspace's n must be a positive integer")
    if kind == "linspace" and args[2] > MAX_RUNS:
        raise ValueError(
            f"{origin} {key}: linspace of {args[2]:.6g} points, more than the {MAX_RUNS} runs "
            "a campaign may have"
        )
    if kind in ("rotate", "inertia") and mode:
        raise ValueError(
            f"{origin} {key}: {kind} already acts on the nominal value; drop the {mode!r}"
        )
    return Dispersion(key, kind, tuple(args), mode, f"{key}={expression.strip()}")


def load(path) -> tuple[list[Dispersion], dict]:
    """(dispersions, fixed values) from a TOML or JSON file: a table ``[vary]`` (TOML) /
    an object ``{"vary": {...}}`` (JSON) mapping ``"Instance.variable"`` to a DIST string,
    and an optional table ``[set]`` of values as for ``--set``."""
    path = Path(path)
    try:
        if path.suffix == ".toml":
            try:
                import tomllib
            except ModuleNotFoundError:  # Python 3.10
                import tomli as tomllib
            data = tomllib.loads(path.read_text())
        elif path.suffix == ".json":
            data = json.loads(path.read_text())
        else:
            raise ValueError(f"{path}: a dispersion file is .toml or .json")
    except (OSError, ValueError) as exc:  # TOMLDecodeError and JSONDecodeError are these
        raise ValueError(f"{path}: {exc}") from None
    vary = data.get("vary") if isinstance(data, dict) else None
    if not isinstance(vary, dict) or not vary:
        raise ValueError(
            f'{path}: expected a table \'vary\' of "Instance.variable" = "DIST" entries'
        )
    result = []
    for key, expression in vary.items():
        if not isinstance(expression, str) or not _KEY.match(key):
            raise ValueError(f'{path}: vary.{key}: expected "Instance.variable" = "DIST"')
        result.append(expression_to_dispersion(key, expression, str(path)))
    fixed = data.get("set", {})
    if not isinstance(fixed, dict) or not all(
        _KEY.match(k) and isinstance(v, (int, float, bool)) for k, v in fixed.items()
    ):
        raise ValueError(f"{path}: 'set' must map \"Instance.variable\" to numbers")
    for key, value in fixed.items():
        if not math.isfinite(value):  # TOML's nan and inf, JSON's NaN
            raise ValueError(f"{path}: set.{key} = {value}: a value must be a finite number")
    return result, fixed


def rotate_rows(nominal: np.ndarray, sd: float, rng) -> np.ndarray:
    """Each row (a unit 3-vector) turned by a small random rotation ⊥ to it (Rodrigues)."""
    vectors = np.atleast_2d(nominal)
    out = np.empty_like(vectors)
    for i, v in enumerate(vectors):
        u = v / np.linalg.norm(v)
        e1 = np.cross(u, np.eye(3)[int(np.argmin(np.abs(u)))])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(u, e1)
        phi = sd * (rng.standard_normal() * e1 + rng.standard_normal() * e2)
        out[i] = rodrigues(phi) @ v
    return out.reshape(nominal.shape)


def rodrigues(phi) -> np.ndarray:
    """Rotation matrix of the rotation vector phi."""
    angle = float(np.linalg.norm(phi))
    if angle == 0.0:
        return np.eye(3)
    k = np.asarray(phi) / angle
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def disperse_inertia(nominal: np.ndarray, sd_rel: float, sd_angle: float, rng) -> np.ndarray:
    moments, axes = np.linalg.eigh(nominal)
    for _ in range(1000):
        drawn = moments * (1 + sd_rel * rng.standard_normal(3))
        if drawn.min() > 0 and 2 * drawn.max() <= drawn.sum():
            break
    else:
        raise ValueError(f"inertia({sd_rel}, {sd_angle}): no physical inertia in 1000 draws")
    R = rodrigues(sd_angle * rng.standard_normal(3)) @ axes
    J = R @ np.diag(drawn) @ R.T
    return (J + J.T) / 2
