"""The 3-D view of a run: where the spacecraft is, where it points, how its actuators move,
with a time slider and a play button (a plotly figure with one frame per shown time).

Frames (DESIGN.md §2): ``q_BI`` maps I-coordinates to B-coordinates, ``v_B = C(q_BI)
v_I`` with ``C(q) = (q0² − q·q) 1 + 2 q qᵀ − 2 q0 [q×]`` (:func:`..frames.dcm`); the Earth-fixed
frame E is I turned by the Earth angle θ_E about z, ``C_EI = R3(θ_E)``; the orbit frame O
is given by ``q_OI``.  Three panels share the slider:

- **the orbit** in E (km), where the run records ``r_I`` and ``earth_angle``: the WGS-84
  ellipsoid under the run (a graticule every 10°; no coastlines), the orbit arc of the
  run, the spacecraft, each boresight's ray to where it meets the ellipsoid (3 median
  slant ranges long where it misses the Earth), that point's ground track, and the
  ground target where the run has one (``r_T_I``);
- **the spacecraft** in O (x ≈ along track, z to nadir, drawn downwards), or in I
  without an orbit frame: the body axes (x red, y green, z blue), the reference attitude
  as a grey ghost where the run records one (an output ``q_ref``, taken as q_RI), the
  boresight cone (its half-angle :data:`CONE` is for display, not a field of view), the
  line of sight to the target and the CMG cluster's momentum ``h`` (scaled to the
  longest of the run);
- **the actuators**: the CMG gimbal angles (or the wheel speeds) against time, the shown
  time marked.

Boresights: the payloads' recorded ``los_B`` (two payloads), else the guidance's
``boresight_B`` parameter, else +z_B.
"""

from __future__ import annotations

import math

import numpy as np

from ...output.frames import dcm, r3
from . import figures
from .decimate import min_max

#: WGS-84 semi-major axis [km] and flattening
WGS84_A, WGS84_F = 6378.137, 1 / 298.257223563
WGS84_B = WGS84_A * (1 - WGS84_F)
#: the most frames (shown times) a view holds
FRAMES = 120
#: the boresight cone's half-angle as drawn (display only)
CONE = math.radians(6.0)
AXIS_COLOURS = ("#d62728", "#2ca02c", "#1f77b4")  # x, y, z
GHOST = "rgba(120,120,120,0.45)"
ORANGE, PURPLE = "#ff7f0e", "#9467bd"


def ellipsoid_hit(p, d) -> np.ndarray:
    """The distance s ≥ 0 along unit rays p + s d (N, 3; km) to the WGS-84 ellipsoid, NaN
    where a ray misses it: the smaller root of |D (p + s d)|² = 1, D = diag(1/a, 1/a, 1/b)."""
    scale = np.array([1 / WGS84_A, 1 / WGS84_A, 1 / WGS84_B])
    P, V = p * scale, d * scale
    a, b, c = (V * V).sum(1), 2 * (P * V).sum(1), (P * P).sum(1) - 1
    disc = b * b - 4 * a * c
    with np.errstate(invalid="ignore"):
        s = (-b - np.sqrt(disc)) / (2 * a)
    return np.where((disc >= 0) & (s >= 0), s, np.nan)


def geodetic_surface(lat, lon):
    """WGS-84 surface points (h = 0) of geodetic ``lat``, ``lon`` [rad], km."""
    e2 = WGS84_F * (2 - WGS84_F)
    N = WGS84_A / np.sqrt(1 - e2 * np.sin(lat) ** 2)
    return N * np.cos(lat) * np.cos(lon), N * np.cos(lat) * np.sin(lon), N * (1 - e2) * np.sin(lat)


def column(results, suffix: str, prefer: str | None = None) -> str | None:
    """The recorded variable (base name) ending in ``.suffix``, ``prefer``'s first."""
    bases = dict.fromkeys(n.partition("[")[0] for n in results.names[1:])
    found = sorted(
        (b for b in bases if b.endswith("." + suffix)), key=lambda b: b.split(".")[0] != prefer
    )
    return found[0] if found else None


def available(results) -> bool:
    """Whether a run recorded what the view needs: an attitude ``q_BI``."""
    return len(results) > 1 and column(results, "q_BI", "SatelliteDynamics") is not None


def boresights(results, parameter) -> list[tuple[str, np.ndarray]]:
    """[(label, unit vectors (N, 3) in B)] (module); ``parameter(name)``: a parameter's
    value as the run had it, or None."""
    los = column(results, "los_B")
    n = len(results)
    if los is not None:
        values = results.vector(los).reshape(n, -1, 3)
        return [(f"payload {k + 1} boresight", values[:, k]) for k in range(values.shape[1])]
    given = [parameter(f"StaringGuidance.boresight_B[{k}]") for k in (1, 2, 3)]
    b = np.array([float(x) for x in given]) if None not in given else np.array([0.0, 0, 1])
    return [("boresight", np.tile(b / np.linalg.norm(b), (n, 1)))]


class _Figure:
    """A figure being built: traces, the layout, and the traces the frames update."""

    def __init__(self):
        self.data: list[dict] = []
        self.layout: dict = {"annotations": [], "margin": {"l": 10, "r": 10, "t": 36, "b": 10}}
        self.animated: list[tuple[int, object]] = []  # (trace index, its data at sample k)

    def add(self, trace: dict, where: str, at=None) -> None:
        """Add ``trace`` to the panel ``where`` (a scene, or "xy"); ``at(k)``: its data at
        sample k, for the frames (its data now: at the first)."""
        if where == "xy":
            trace.update(xaxis="x", yaxis="y")
        else:
            trace["scene"] = where
        if at is not None:
            self.animated.append((len(self.data), at))
        self.data.append(trace)

    def title(self, text: str, x: float, y: float) -> None:
        self.layout["annotations"].append(
            {
                "text": text,
                "x": x,
                "y": y,
                "xref": "paper",
                "yref": "paper",
                "xanchor": "center",
                "yanchor": "bottom",
                "showarrow": False,
                "font": {"size": 14},
            }
        )


def figure(results, parameter=lambda name: None) -> dict:
    """The view (module) as a plotly figure (dict, :mod:`.figures`) with its frames."""
    t = results.time
    n = len(t)
    shown = np.unique(np.linspace(0, n - 1, min(FRAMES, n)).round().astype(int))
    C_BI = dcm(results.vector(column(results, "q_BI", "SatelliteDynamics")))
    r_name, theta = column(results, "r_I"), column(results, "earth_angle")
    orbit = r_name is not None and theta is not None
    actuators = _actuators(results)
    fig = _Figure()
    bottom = 0.36 if actuators else 0.0
    looks = boresights(results, parameter)
    k0 = int(shown[0])
    if orbit:
        fig.layout["scene"] = {"domain": {"x": [0, 0.49], "y": [bottom, 0.96]}}
        fig.title("orbit and boresight, Earth-fixed frame E [km]", 0.245, 0.965)
        _orbit_view(fig, results, C_BI, looks, r_name, theta, k0)
    attitude_scene = "scene2" if orbit else "scene"
    right = 0.81  # the legend beside it
    fig.layout[attitude_scene] = {
        "domain": {"x": [0.5 if orbit else 0, right], "y": [bottom, 0.96]}
    }
    q_oi = column(results, "q_OI")
    fig.title(
        f"attitude in the {'orbit frame O' if q_oi else 'inertial frame I'}",
        (0.5 + right) / 2 if orbit else right / 2,
        0.965,
    )
    _attitude_view(fig, results, C_BI, looks, q_oi, attitude_scene, k0)
    if actuators:
        _actuator_panel(fig, t, actuators, k0)
    frames = [
        {
            "name": str(k),
            "data": [at(k) for _, at in fig.animated],
            "traces": [index for index, _ in fig.animated],
        }
        for k in shown
    ]
    step = {
        "mode": "immediate",
        "frame": {"duration": 0, "redraw": True},
        "transition": {"duration": 0},
    }
    fig.layout.update(
        height=960 if actuators else 700,
        showlegend=True,
        legend={
            "x": 1.0,
            "xanchor": "right",
            "y": bottom + 0.01 if actuators else 0.0,
            "yanchor": "bottom",
            "font": {"size": 10},
            "bgcolor": "rgba(255,255,255,0.75)",
        },
        sliders=[
            {
                "active": 0,
                "name": "time",
                "x": 0.08,
                "len": 0.92,
                "y": 0,
                "yanchor": "top",
                "pad": {"t": 36},
                "currentvalue": {"prefix": "t = ", "suffix": " s"},
                "font": {"size": 9},
                "steps": [
                    {"method": "animate", "label": f"{t[k]:.4g}", "args": [[str(k)], step]}
                    for k in shown
                ],
            }
        ],
        updatemenus=[
            {
                "type": "buttons",
                "showactive": False,
                "direction": "left",
                "x": 0.0,
                "y": 0,
                "xanchor": "left",
                "yanchor": "top",
                "pad": {"t": 60},
                "buttons": [
                    {
                        "label": "▶",
                        "method": "animate",
                        "args": [
                            None,
                            {
                                **step,
                                "frame": {"duration": 80, "redraw": True},
                                "fromcurrent": True,
                                "mode": "immediate",
                            },
                        ],
                    },
                    {"label": "❚❚", "method": "animate", "args": [[None], step]},
                ],
            }
        ],
    )
    fig.layout["margin"]["b"] = 90
    return {"data": fig.data, "layout": fig.layout, "frames": frames}


def _points(p, **more) -> dict:
    """scatter3d data of points p (n, 3)."""
    return {
        "type": "scatter3d",
        "x": figures.array(p[:, 0]),
        "y": figures.array(p[:, 1]),
        "z": figures.array(p[:, 2]),
        **more,
    }


def _segment(v, start=(0.0, 0.0, 0.0)) -> dict:
    return _points(np.array([start, v], float))


def _orbit_view(fig: _Figure, results, C_BI, looks, r_name, theta_name, k0: int) -> None:
    """The orbit panel (module)."""
    C_EI = r3(results[theta_name])
    r_E = np.einsum("nij,nj->ni", C_EI, results.vector(r_name)) / 1e3  # km
    rays = []
    for label, b_B in looks:
        d_E = np.einsum("nij,nj->ni", C_EI, np.einsum("nji,nj->ni", C_BI, b_B))  # C_EI C_BIᵀ b
        rays.append((label, d_E, ellipsoid_hit(r_E, d_E)))
    target = column(results, "r_T_I")
    points = [r_E] + [r_E + d * s[:, None] for _, d, s in rays]
    if target is not None:
        target_E = np.einsum("nij,nj->ni", C_EI[:1], results.vector(target)[:1]) / 1e3
        points.append(target_E)
    box = np.vstack([p[np.isfinite(p).all(1)] for p in points])
    low, high = box.min(0), box.max(0)
    pad = np.maximum(0.3 * (high - low).max(), 300.0)
    low, high = low - pad, high + pad
    _earth(fig, low, high)
    fig.add(
        _points(
            r_E[:: max(1, len(r_E) // 500)],
            mode="lines",
            name="orbit arc of the run",
            line={"color": "#333", "width": 3},
        ),
        "scene",
    )
    for label, d_E, s in rays:
        ground = r_E + d_E * s[:, None]
        fig.add(
            _points(
                ground[:: max(1, len(ground) // 500)],
                mode="lines",
                name=f"ground track of the {label}",
                line={"color": ORANGE, "width": 3},
            ),
            "scene",
        )
    if target is not None:
        fig.add(
            _points(
                target_E,
                mode="markers",
                name="ground target",
                marker={"size": 5, "color": PURPLE, "symbol": "diamond"},
            ),
            "scene",
        )
    fig.add(
        _points(
            r_E[k0 : k0 + 1],
            mode="markers",
            name="spacecraft",
            marker={"size": 6, "color": "black"},
        ),
        "scene",
        at=lambda k: _points(r_E[k : k + 1]),
    )
    reaches = [float(np.nanmedian(s)) for _, _, s in rays if np.isfinite(s).any()]
    reach = 3 * (reaches[0] if reaches else 1000.0)
    for label, d_E, s in rays:
        end = r_E + d_E * np.where(np.isfinite(s), s, reach)[:, None]

        def ray(k, end=end):
            return _segment(end[k], r_E[k])

        fig.add(
            {
                **ray(k0),
                "mode": "lines",
                "name": f"{label} to the ground",
                "line": {"color": ORANGE, "width": 6},
            },
            "scene",
            at=ray,
        )
    span = high - low
    fig.layout["scene"].update(
        xaxis={"range": [low[0], high[0]], "title": {"text": "x_E [km]"}},
        yaxis={"range": [low[1], high[1]], "title": {"text": "y_E [km]"}},
        zaxis={"range": [low[2], high[2]], "title": {"text": "z_E [km]"}},
        aspectmode="manual",
        aspectratio=dict(zip("xyz", (span / span.max()).tolist())),
    )


def _earth(fig: _Figure, low, high) -> None:
    """The WGS-84 ellipsoid under the box [low, high] (km): a surface patch and a
    graticule every 10°."""
    corners = np.array(
        [[x, y, z] for x in (low[0], high[0]) for y in (low[1], high[1]) for z in (low[2], high[2])]
    )
    lon0, lon1 = _span_of_angles(np.degrees(np.arctan2(corners[:, 1], corners[:, 0])))
    lat = np.degrees(np.arctan2(corners[:, 2], np.hypot(corners[:, 0], corners[:, 1])))
    lat0, lat1 = max(lat.min() - 3, -90.0), min(lat.max() + 3, 90.0)
    lons = np.radians(np.linspace(lon0 - 3, lon1 + 3, 70))
    lats = np.radians(np.linspace(lat0, lat1, 50))
    x, y, z = geodetic_surface(*np.meshgrid(lats, lons, indexing="ij"))
    inside = (
        (x >= low[0])
        & (x <= high[0])
        & (y >= low[1])
        & (y <= high[1])
        & (z >= low[2])
        & (z <= high[2])
    )
    shown = _grid(np.where(inside, z, np.nan))  # outside the box: not drawn
    fig.add(
        {
            "type": "surface",
            "x": _grid(x),
            "y": _grid(y),
            "z": shown,
            "surfacecolor": shown,
            "showscale": False,
            "opacity": 0.95,
            "colorscale": [[0, "#a9c8e6"], [1, "#c9dcef"]],
            "hoverinfo": "skip",
            "name": "Earth (WGS-84)",
            "showlegend": True,
        },
        "scene",
    )
    xs, ys, zs = [], [], []
    for value in np.arange(math.ceil(lat0 / 10) * 10, lat1, 10):
        xs, ys, zs = _polyline(
            xs,
            ys,
            zs,
            np.full(90, math.radians(value)),
            np.linspace(lons[0], lons[-1], 90),
            low,
            high,
        )
    for value in np.arange(math.ceil((lon0 - 3) / 10) * 10, lon1 + 3, 10):
        xs, ys, zs = _polyline(
            xs,
            ys,
            zs,
            np.linspace(lats[0], lats[-1], 60),
            np.full(60, math.radians(value)),
            low,
            high,
        )
    if xs:
        fig.add(
            {
                "type": "scatter3d",
                "mode": "lines",
                "x": figures.array(xs),
                "y": figures.array(ys),
                "z": figures.array(zs),
                "hoverinfo": "skip",
                "line": {"color": "rgba(50,70,100,0.5)", "width": 1.5},
                "name": "graticule (10°)",
            },
            "scene",
        )


def _grid(values) -> list:
    """A 2-D grid as nested lists (a surface's), NaN as None."""
    return [[None if not math.isfinite(v) else round(float(v), 3) for v in row] for row in values]


def _polyline(xs, ys, zs, lat, lon, low, high):
    """Append a graticule line (a NaN after it), slightly above the surface, clipped to
    the box."""
    x, y, z = (c * 1.0008 for c in geodetic_surface(lat, lon))
    out = (x < low[0]) | (x > high[0]) | (y < low[1]) | (y > high[1]) | (z < low[2]) | (z > high[2])
    for c, values in ((xs, x), (ys, y), (zs, z)):
        c.extend(np.where(out, np.nan, values).tolist() + [math.nan])
    return xs, ys, zs


def _span_of_angles(deg) -> tuple[float, float]:
    """The smallest interval of longitudes [°] holding all of ``deg`` (across ±180°)."""
    a = np.sort(np.mod(deg, 360.0))
    gaps = np.diff(np.r_[a, a[0] + 360])
    k = int(np.argmax(gaps))
    start = a[(k + 1) % len(a)]
    return float(start), float(start + 360 - gaps[k])


def _attitude_view(fig: _Figure, results, C_BI, looks, q_oi, where: str, k0: int) -> None:
    """The spacecraft panel (module)."""
    if q_oi is not None:
        C_OI = dcm(results.vector(q_oi))
        view = lambda C: np.einsum("nij,nkj->nik", C, C_OI)  # noqa: E731  C_XO = C_XI C_OIᵀ
        names = ("x_O along track", "y_O", "z_O nadir")
    else:
        C_OI = None
        view = lambda C: C  # noqa: E731
        names = ("x_I", "y_I", "z_I")
    C_BV = view(C_BI)  # rows: the body axes in view coordinates
    for axis, name in enumerate(names):
        tip = np.eye(3)[axis] * 1.9
        fig.add(
            {
                **_segment(tip),
                "mode": "lines+text",
                "text": ["", name],
                "line": {"color": "#b5b5b5", "width": 2},
                "textfont": {"size": 11, "color": "#666"},
                "hoverinfo": "skip",
                "showlegend": False,
            },
            where,
        )
    reference = column(results, "q_ref")
    if reference is not None:
        C_RV = view(dcm(results.vector(reference)))
        for axis in range(3):

            def ghost(k, axis=axis):
                return _segment(C_RV[k, axis] * 1.15)

            fig.add(
                {
                    **ghost(k0),
                    "mode": "lines",
                    "line": {"color": GHOST, "width": 12},
                    "name": "reference attitude (ghost)",
                    "legendgroup": "ghost",
                    "showlegend": axis == 0,
                },
                where,
                at=ghost,
            )
    for axis, (colour, label) in enumerate(zip(AXIS_COLOURS, "xyz")):

        def body(k, axis=axis):
            return _segment(C_BV[k, axis])

        fig.add(
            {
                **body(k0),
                "mode": "lines",
                "line": {"color": colour, "width": 7},
                "name": f"body {label}_B",
            },
            where,
            at=body,
        )
    for label, b_B in looks:
        b_V = np.einsum("nji,nj->ni", C_BV, b_B)  # C_BVᵀ b_B

        def cone(k, b_V=b_V):
            return _cone(b_V[k], 1.6)

        fig.add(
            {
                **cone(k0),
                "color": ORANGE,
                "opacity": 0.35,
                "hoverinfo": "skip",
                "name": f"{label} cone (drawn {math.degrees(CONE):g}°)",
                "showlegend": True,
            },
            where,
            at=cone,
        )
    r_name, target = column(results, "r_I"), column(results, "r_T_I")
    if r_name is not None and target is not None:
        los_I = results.vector(target) - results.vector(r_name)
        los_I /= np.linalg.norm(los_I, axis=1)[:, None]
        los_V = los_I if C_OI is None else np.einsum("nij,nj->ni", C_OI, los_I)

        def sight(k):
            return _segment(los_V[k] * 2.0)

        fig.add(
            {
                **sight(k0),
                "mode": "lines",
                "name": "line of sight to the target",
                "line": {"color": PURPLE, "width": 3, "dash": "dash"},
            },
            where,
            at=sight,
        )
    h_name = column(results, "h", "CmgCluster")
    if h_name is not None and h_name.startswith("CmgCluster."):
        h_B = results.vector(h_name)
        h_max = float(np.linalg.norm(h_B, axis=1).max()) or 1.0
        h_V = np.einsum("nji,nj->ni", C_BV, h_B) / h_max * 1.2

        def momentum(k):
            return _segment(h_V[k])

        fig.add(
            {
                **momentum(k0),
                "mode": "lines",
                "line": {"color": "#8c564b", "width": 5},
                "name": f"CMG momentum h (longest {h_max:.3g} N·m·s)",
            },
            where,
            at=momentum,
        )
    box = {"range": [-2.1, 2.1], "showticklabels": False, "title": {"text": ""}}
    fig.layout[where].update(xaxis=box, yaxis=dict(box), zaxis=dict(box), aspectmode="cube")
    if q_oi is not None:  # nadir down, looking across the track (orbit: any up)
        fig.layout[where]["dragmode"] = "orbit"
        fig.layout[where]["camera"] = {
            "up": {"x": 0, "y": 0, "z": -1},
            "eye": {"x": 0.7, "y": -1.9, "z": -0.8},
        }


def _cone(axis, length: float, sides: int = 24) -> dict:
    """mesh3d data of a cone with its apex at the origin along ``axis``."""
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    u = np.cross(axis, [1.0, 0, 0] if abs(axis[0]) < 0.9 else [0, 1.0, 0])
    u /= np.linalg.norm(u)
    w = np.cross(axis, u)
    phi = np.linspace(0, 2 * np.pi, sides, endpoint=False)
    rim = length * axis + length * math.tan(CONE) * (
        np.outer(np.cos(phi), u) + np.outer(np.sin(phi), w)
    )
    p = np.vstack([np.zeros(3), rim])
    return {
        "type": "mesh3d",
        "x": figures.array(p[:, 0]),
        "y": figures.array(p[:, 1]),
        "z": figures.array(p[:, 2]),
        "i": [0] * sides,
        "j": list(range(1, sides + 1)),
        "k": [*range(2, sides + 1), 1],
    }


def _actuators(results):
    """(axis title, element label, values (N, k)) of the CMG gimbal angles [°] or the
    wheel speeds [rpm], or None."""
    delta = column(results, "delta", "CmgCluster")
    if delta is not None:
        return ("CMG gimbal angles δ [°]", "gimbal", np.degrees(results.vector(delta)))
    speed = column(results, "speed", "Flywheel")
    if speed is not None:
        return ("reaction wheel speeds [rpm]", "wheel", results.vector(speed) * 30 / math.pi)
    return None


def _actuator_panel(fig: _Figure, t, actuators, k0: int) -> None:
    """The actuators against time, the shown time as a vertical line."""
    title, label, values = actuators
    for j in range(values.shape[1]):
        x, y = min_max(t, values[:, j], 500)
        fig.add(
            figures.line(
                x,
                y,
                f"{label} {j + 1}",
                figures.COLOURS[j % 9],
                showlegend=False,
                hovertemplate=f"{label} {j + 1}: %{{y:.4g}}<extra></extra>",
            ),
            "xy",
        )
    low, high = float(np.nanmin(values)), float(np.nanmax(values))
    pad = 0.05 * (high - low or 1.0)

    def cursor(k):
        return {"type": "scatter", "x": [t[k], t[k]], "y": [low - pad, high + pad]}

    fig.add(
        {
            **cursor(k0),
            "mode": "lines",
            "line": {"color": "black", "width": 1.5},
            "name": "shown time",
            "showlegend": False,
        },
        "xy",
        at=cursor,
    )
    fig.layout["xaxis"] = {"domain": [0.06, 1], "anchor": "y", "title": {"text": "time [s]"}}
    fig.layout["yaxis"] = {"domain": [0.0, 0.27], "anchor": "x", "title": {"text": title}}
