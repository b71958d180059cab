"""``agilesat report``'s parts that need no run (the fast layer): series thinned with their
extremes kept, the typed arrays plotly.js reads, the page's escaping, the frames of the 3-D
view against DESIGN.md §2's own functions and the WGS-84 ellipsoid's closed forms."""

import base64
import json
import math

import numpy as np
import pytest

from agilesat.components.rotations import dcm as dcm_one
from agilesat.orchestration.output.frames import dcm, r3, turn_z
from agilesat.orchestration.postprocess.report import figures
from agilesat.orchestration.postprocess.report.decimate import indices, min_max
from agilesat.orchestration.postprocess.report.page import Page
from agilesat.orchestration.postprocess.report.scene import WGS84_A, WGS84_B, ellipsoid_hit


@pytest.mark.parametrize("buckets", [7, 50, 333])
def test_thinning_keeps_each_bucket_s_extremes(buckets):
    rng = np.random.default_rng(buckets)
    n = 20_000
    y = np.cumsum(rng.normal(size=n))
    y[rng.integers(0, n, 5)] += rng.choice([-1, 1], 5) * 300  # one-sample spikes
    t = np.arange(n) * 0.01
    x, kept = min_max(t, y, buckets)
    assert len(kept) <= 2 * buckets + 2
    assert np.all(np.diff(x) > 0)  # in time order
    edges = np.linspace(0, n, buckets + 1).astype(int)
    for a, b in zip(edges[:-1], edges[1:]):  # every bucket: its min and max are drawn
        inside = (x >= t[a]) & (x <= t[b - 1])
        assert kept[inside].min() == y[a:b].min() and kept[inside].max() == y[a:b].max()
    assert set(kept) <= set(y)  # nothing drawn that the series does not take


def test_thinning_keeps_a_gap_and_leaves_short_series_alone():
    y = np.sin(np.linspace(0, 20, 5000))
    y[2000:2600] = np.nan  # a run that stopped, say
    keep = indices(y, 20)
    assert np.isnan(y[keep]).sum() == 1 and keep[np.isnan(y[keep])][0] == 2000
    assert np.array_equal(indices(y[:30], 20), np.arange(30))


def test_typed_arrays_are_float32_base64():
    values = np.array([1.5, -2.25, np.nan, 1e-30])
    spec = figures.array(values)
    decoded = np.frombuffer(base64.b64decode(spec["bdata"]), "<f4")
    assert spec["dtype"] == "f4"
    np.testing.assert_array_equal(decoded, values.astype("<f4"))


def test_a_page_keeps_its_data_inside_its_scripts():
    page = Page("a </script> title")
    page.figure({"data": [{"type": "scatter", "name": "</script><b>x</b>"}], "layout": {}})
    page.table(["name"], [["</script>"]])
    text = "\n".join(page.parts)
    assert text.count("</script>") == 2  # only the two data scripts' own ends
    spec = text.split('id="figure-1">', 1)[1].split("</script>", 1)[0]
    assert json.loads(spec)["data"][0]["name"] == "</script><b>x</b>"


def test_the_frames_are_design_s():
    rng = np.random.default_rng(1)
    q = rng.normal(size=(50, 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    for C, one in zip(dcm(q), q):
        np.testing.assert_allclose(C, np.array(dcm_one(one)), atol=1e-15)
    angles = rng.uniform(-7, 7, 10)
    for C, angle in zip(r3(angles), angles):
        np.testing.assert_allclose(C, dcm(turn_z(angle)[None])[0], atol=1e-15)
        np.testing.assert_allclose(C @ [1.0, 0, 0], [math.cos(angle), -math.sin(angle), 0])


def test_rays_meet_the_wgs84_ellipsoid_where_its_closed_forms_say():
    h = 700.0
    p = np.array([[0, 0, WGS84_B + h], [WGS84_A + h, 0, 0], [WGS84_A + h, 0, 0]])
    d = np.array([[0, 0, -1.0], [-1.0, 0, 0], [0, 1.0, 0]])
    s = ellipsoid_hit(p, d)
    np.testing.assert_allclose(s[:2], [h, h], rtol=1e-12)
    assert np.isnan(s[2])  # along the horizon, outside the Earth: a miss
    slant = np.array([[WGS84_A + h, 0, 0]])
    look = np.array([[-math.cos(0.5), math.sin(0.5), 0]])  # 0.5 rad off nadir, equatorial
    hit = slant + look * ellipsoid_hit(slant, look)[:, None]
    assert abs(np.hypot(hit[0, 0], hit[0, 1]) - WGS84_A) < 1e-9
