"""The ``flexible`` variants of scan_pitch and video_sar: the same satellite with two
solar-array wings (six modes of the hub, DESIGN.md §3.2) and imbalanced CMG rotors (their
jitter in a row of the hub), and the imaging window's stability, RPE and PDE
([Ecss 2008] §3.2), which every run of both scenarios reports (docs/jitter.md).

The wings.  Two wings of three panels each, fixed on ±x_B with their cells facing −y_B:
the orbits are near the terminator (video_sar's pass is ascending at 16:48 local time,
[Liang 2019] through passes.design_pass), where the Sun stays near the orbit normal −y_O.
Their deployed frequencies are those measured on the IRS satellite's six-panel wings
([Das 1988]: out-of-plane bending 0.39 Hz, in-plane bending 1.07 Hz, torsion 3.3 Hz), their
damping ratios those of MOS-1's paddle on orbit ([Mos 1985]: 1.1 %, 0.4 %, 0.45 % of its
first three modes; [Buckingham 1975] measured 0.1–1 % on CTS's array).  Their mass
distribution is ours (the sources give none): 12 kg a wing over a span of 3.9 m (three
1.3 m panels) from a root 1.0 m off the centre of mass, 1.1 m wide; each mode shape the
uniform cantilever's ([Blevins 1979] table 8-1: φ = cosh βx − cos βx − σ (sinh βx −
sin βx), βℓ = 1.87510, σ = 0.734096; torsion θ = sin(πx / 2ℓ)), whose participation factors
have closed forms (:func:`bending_participation`, :func:`torsion_participation`).  A wing
along +x bending out of plane (along y) turns the body about z, in plane (along z) about −y,
twisting about x; the wing on −x mirrors it.  ``inertia`` (956 kg·m² on each axis) stays the
whole spacecraft's: the hub alone is J − Σ L_kᵀ L_k (740 kg·m² about y and z).

The rotors.  Each of the six CMG rotors has the imbalance of the Honeywell HR12 wheel of
25 N·m·s (U_s = 2.4e-6 kg·m, U_d = 4.6e-7 kg·m², its datasheet's figures as Basilisk's
simIncludeRW tabulates them; our rotors, 16.65 N·m·s at 6000 rpm, are between its 12 and
25 N·m·s sizes), spinning at 6000 rpm; their centres on a ring of 0.6 m radius 0.5 m
below the centre of mass at their gimbals' azimuths, the sixth 0.8 m below it, their
phases 60° apart (ours).

Stability over the imaging window: the performance error e(t) (scan_pitch: the body from
the planned attitude, 3-axis; video_sar: the radar's line of sight from the guidance's, half
cone), RPE = e(t) − ē(Δt) and PDE = ē(Δt₂) − ē(Δt₁) with Δt = 1 s (the duration of an image
line block; ours), Δt_s = 1 s, t at a window's end, the largest over the window.  The
rotors' jitter at 100 Hz is not in them: the records' samples, every 0.05 s, fall at one
phase of it (100 Hz is 5 × 20 Hz); ``cmg_jitter`` gives its amplitude, the body's steady
response (components/satellite_dynamics.py), which an RPE over Δt ≫ 10 ms adds to at most.
"""

from __future__ import annotations

import math

import numpy as np

from agilesat.components.cmg_cluster import N_GYROS, PYRAMID_AZIMUTHS
from agilesat.components.satellite_dynamics import N_MODES
from agilesat.orchestration.mission import Metric, NotEvaluable, Variant, panels
from agilesat.orchestration.output.results import per_results
from agilesat.orchestration.pointing import ErrorHistory, index_series, magnitude

DEG = math.pi / 180
ARCSEC = DEG / 3600
#: [Das 1988]: the IRS wing's deployed frequencies (Hz): out-of-plane and in-plane bending,
#: torsion
WING_FREQUENCIES = (0.39, 1.07, 3.3)
#: [Mos 1985]: MOS-1's paddle, its first three modes on orbit
WING_DAMPING = (0.011, 0.004, 0.0045)
#: ours: a wing's mass (kg), span, root offset from the centre of mass and width (m)
WING = {"mass": 12.0, "span": 3.9, "root": 1.0, "width": 1.1}
#: the uniform cantilever's first bending mode ([Blevins 1979] table 8-1)
BETA_L, SIGMA = 1.87510407, 0.734095514
#: HR12-25 (Honeywell; Basilisk's simIncludeRW): static and dynamic imbalance
STATIC_IMBALANCE, DYNAMIC_IMBALANCE = 2.4e-6, 4.6e-7  # kg·m, kg·m²
#: ours: where the rotors are
ROTOR_RING, ROTOR_DEPTH, SIXTH_DEPTH = 0.6, 0.5, 0.8  # m
#: the stability indices' windows (s)
WINDOW, SEPARATION = 1.0, 1.0


def bending_participation(mass: float, span: float, root: float) -> float:
    """L of a uniform cantilever's first bending mode about an axis ``root`` from its
    clamp, mass-normalised: ψ = φ / √(μ ℓ) (∫₀ˡ φ² dx = ℓ), so that
    L = ∫ μ (root + x) ψ dx = √(μ / ℓ) (root · 2σℓ / βℓ + 2ℓ² / (βℓ)²)
    (∫₀ˡ φ dx = 2σℓ / βℓ, ∫₀ˡ x φ dx = 2ℓ² / (βℓ)²)."""
    mu = mass / span
    return math.sqrt(mu / span) * (root * 2 * SIGMA * span / BETA_L + 2 * span**2 / BETA_L**2)


def torsion_participation(mass: float, span: float, width: float) -> float:
    """L of a uniform plate's first torsion mode about its axis: θ = sin(π x / 2ℓ),
    polar inertia j = μ b² / 12 per length, ψ = θ √(2 / (j ℓ)), L = ∫ j ψ dx =
    (2 / π) √(2 j ℓ)."""
    j = mass / span * width**2 / 12
    return 2 / math.pi * math.sqrt(2 * j * span)


def wing_modes() -> dict:
    """The hub's modal parameters (module docstring): wing +x then wing −x, each
    out-of-plane bending, in-plane bending, torsion."""
    bending = bending_participation(WING["mass"], WING["span"], WING["root"])
    twist = torsion_participation(WING["mass"], WING["span"], WING["width"])
    rows = []
    for side in (1.0, -1.0):  # r = side x: r × ŷ = side ẑ, r × ẑ = −side ŷ, twist about side x
        rows += [(0.0, 0.0, side * bending), (0.0, -side * bending, 0.0), (side * twist, 0.0, 0.0)]
    frequency = [2 * math.pi * f for f in WING_FREQUENCIES] * 2
    return {
        "SatelliteDynamics.modal_frequency": frequency + [0.0] * (N_MODES - 6),
        "SatelliteDynamics.modal_damping": list(WING_DAMPING) * 2 + [0.0] * (N_MODES - 6),
        "SatelliteDynamics.modal_coupling": rows + [(0.0, 0.0, 0.0)] * (N_MODES - 6),
    }


def rotor_imbalance() -> dict:
    """The CMG rotors' imbalance parameters (module docstring)."""
    ring = [
        (ROTOR_RING * math.cos(a), ROTOR_RING * math.sin(a), ROTOR_DEPTH) for a in PYRAMID_AZIMUTHS
    ]
    return {
        "CmgCluster.static_imbalance": [STATIC_IMBALANCE] * N_GYROS,
        "CmgCluster.dynamic_imbalance": [DYNAMIC_IMBALANCE] * N_GYROS,
        "CmgCluster.rotor_position_B": ring + [(0.0, 0.0, SIXTH_DEPTH)],
        "CmgCluster.imbalance_phase0": [i * 60 * DEG for i in range(N_GYROS)],
    }


PARAMETERS = {**wing_modes(), **rotor_imbalance()}


def with_jitter(system) -> None:
    """The rotors' jitter into the hub's first row of further devices (its frequency too,
    so that the hub takes it as their steady response)."""
    system.connect("CmgCluster.h_jitter_B", "SatelliteDynamics.h_extra[1]")
    system.connect("CmgCluster.hdot_jitter_B", "SatelliteDynamics.hdot_extra[1]")
    system.connect("CmgCluster.jitter_frequency", "SatelliteDynamics.h_extra_frequency[1]")


def stability(error, start: float, stop: float) -> dict:
    """{"RPE": (t, |RPE|), "PDE": (t, |PDE|)} of ``error(results)`` (an ErrorHistory) over
    [start, stop] (module docstring)."""
    t = error.t
    if not len(t) or t[-1] < stop - 1e-9:  # a run ended (--stop, a signal) before its end
        end = f"t = {t[-1]:g} s" if len(t) else "no record"
        raise NotEvaluable(
            f"the records end at {end}, before the imaging window [{start:g}, {stop:g}] s ends"
        )
    inside = (t >= start - 1e-9) & (t <= stop + 1e-9)
    window = ErrorHistory(error.values[:, inside], t[inside], error.kind, error.signal)
    return {
        index: (series.t, magnitude(series)[0])
        for index, series in (
            ("RPE", index_series(window, "RPE", WINDOW)),
            ("PDE", index_series(window, "PDE", WINDOW, SEPARATION)),
        )
    }


@per_results
def imaging_stability(results, error, start: float, stop: float) -> dict:
    """:func:`stability` of ``error(results)``, computed once per results (both indices'
    metrics read it)."""
    return stability(error(results), start, stop)


def stability_metrics(error, start: float, stop: float, what: str) -> list[Metric]:
    """imaging_rpe and imaging_pde: the largest over [start, stop] (module docstring)."""
    return [
        Metric(
            f"imaging_{index.lower()}",
            lambda results, index=index: float(
                imaging_stability(results, error, start, stop)[index][1].max()
            ),
            "rad",
            "arcsec",
            f"max |{index}| of {what} over the imaging window (Δt = {WINDOW:g} s"
            + (f", Δt_s = {SEPARATION:g} s)" if index == "PDE" else ")"),
        )
        for index in ("RPE", "PDE")
    ]


def jitter_amplitude(results) -> np.ndarray:
    """The peak (rad) of the body's steady jitter under the CMG rotors at each sample: the
    largest singular value of M⁻¹ [ḣ_u / Ω², h_u / Ω] (θ̃ and ω̃ / Ω, the harmonic's two
    phases; components/satellite_dynamics.py), M = J − Σ L_kᵀ L_k of the run."""
    parameters = results.meta["parameters"]
    J = np.array([[parameters[f"SatelliteDynamics.inertia[{i},{j}]"] for j in (1, 2, 3)]
                  for i in (1, 2, 3)])  # fmt: skip
    L = np.array([[parameters[f"SatelliteDynamics.modal_coupling[{k},{i}]"] for i in (1, 2, 3)]
                  for k in range(1, N_MODES + 1)])  # fmt: skip
    M_inv = np.linalg.inv(J - L.T @ L)
    speed = results["CmgCluster.jitter_frequency"][:, None]
    phases = np.stack(
        [results.vector("CmgCluster.hdot_jitter_B") / speed**2,
         results.vector("CmgCluster.h_jitter_B") / speed], axis=-1,
    )  # fmt: skip
    return np.linalg.svd(M_inv @ phases, compute_uv=False)[:, 0]


def jitter_metric(start: float, stop: float) -> Metric:
    """cmg_jitter: the largest amplitude of the rotors' jitter over [start, stop]."""

    def compute(results):
        t = results.time
        inside = (t >= start - 1e-9) & (t <= stop + 1e-9)
        return float(jitter_amplitude(results)[inside].max())

    return Metric(
        "cmg_jitter",
        compute,
        "rad",
        "arcsec",
        "amplitude of the body's jitter at the CMG rotors' spin frequency over the imaging "
        "window (their steady response; not in the 20 Hz samples)",
    )


def figure(error, start: float, stop: float, name: str):
    """The stability figure of a flexible run: the error over the imaging window, |RPE|
    and |PDE| (arcsec), and the modes' coordinates η."""

    def draw(results, out_dir):
        indices = stability(error(results), start, stop)
        t = results.time
        inside = (t >= start - 1e-9) & (t <= stop + 1e-9)
        e = np.linalg.norm(error(results).values[0], axis=-1)
        eta = results.vector("SatelliteDynamics.eta")
        rows = [
            (t[inside], {name: e[inside] / ARCSEC}, "error [arcsec]"),
            *(
                (tk, {f"|{index}| (Δt = {WINDOW:g} s)": x / ARCSEC}, f"{index} [arcsec]")
                for index, (tk, x) in indices.items()
            ),
            (
                t[inside],
                {f"η{k + 1}": eta[inside, k] for k in range(6)},
                "modal coordinate [kg^½·m]",
            ),
        ]
        return panels(out_dir / "imaging_stability.png", "Imaging window: stability", rows)

    return draw


def variant(error, start: float, stop: float, name: str) -> Variant:
    """A scenario's ``flexible`` variant: the wings and the rotors, the rotors' jitter
    metric and the stability figure over the imaging window [start, stop] of ``error``
    (named ``name`` in the figure)."""
    return Variant(
        "two solar-array wings (six modes) and imbalanced CMG rotors (their jitter)",
        parameters=PARAMETERS,
        system=with_jitter,
        metrics=[jitter_metric(start, stop)],
        figures=[figure(error, start, stop, name)],
    )
