"""The figures (gearopt.figures) and ``gearopt report``: each figure rendered for seed 001
section 5.3, a tapered face-milled pair and an epicycloid pair, and its data checked against
the analysis it draws."""

from __future__ import annotations

import base64
import math
from html.parser import HTMLParser

import numpy as np
import pytest

import gearopt
from gearopt.cli import main
from gearopt.mesh import ARCSEC, PairCurve
from tests.conftest import STUDIES

pytest.importorskip("matplotlib")

from gearopt.figures import analysis_figures, figure_data  # noqa: E402
from gearopt.figures.draw import MIN_TE_SPAN_ARCSEC  # noqa: E402
from gearopt.plugins import evaluators  # noqa: E402

DESIGNS = {
    "section5_3": STUDIES / "seed001_section5_3.toml",  # cyclo-palloid, uniform depth
    "tapered": STUDIES / "iso23509" / "face_milling_14x39.toml",  # face milling, duplex taper
    "epicycloid": STUDIES / "seed003_case_A.toml",  # epicycloid, conjugate (flat TE)
}
WINDOW_UM = (150.0, 260.0)


@pytest.fixture(scope="module", params=sorted(DESIGNS))
def case(request):
    """A design, its tca/backlash/ease-off evaluations, the figure data and every figure."""
    import matplotlib.pyplot as plt

    design = gearopt.load_design(DESIGNS[request.param])
    registry = evaluators()
    evaluations = {n: registry[n].evaluate(design, {}) for n in ("tca", "backlash", "ease-off")}
    figures = analysis_figures(design, evaluations, window_um=WINDOW_UM)
    yield {
        "name": request.param,
        "design": design,
        "evaluations": evaluations,
        "data": figure_data(design, evaluations["tca"]),
        "figures": figures,
    }
    for fig in figures.values():
        plt.close(fig)


def test_every_figure_is_drawn_and_renders(case, tmp_path):
    assert set(case["figures"]) == {"te", "pattern", "backlash", "ease_off", "misalignment"}
    for name, fig in case["figures"].items():
        path = tmp_path / f"{name}.png"
        fig.savefig(path, dpi=60)
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    titles = [ax.get_title() for ax in case["figures"]["pattern"].axes]
    assert sum(t.startswith("pinion") for t in titles) == 2  # drive and coast
    assert sum(t.startswith("gear") for t in titles) == 2


def test_te_envelope_is_the_reported_te_and_its_peak_to_peak(case):
    data, tca = case["data"], case["evaluations"]["tca"]
    for side, key in (("drive", "tca"), ("coast", "tca_coast")):
        c, report = data["te"][side], tca.report[key]
        # the envelope is the least lag over the pairs shifted to the reported TE: at the
        # analysed positions it is the reported TE (the same field, the same positions)
        field = data["pair"].drive if side == "drive" else data["pair"].coast
        curve = PairCurve(field)
        t = np.radians(report["phi1_deg"])
        ks = np.arange(-6, 7) * curve.pitch
        lag = curve((t[:, None] + ks[None, :]).ravel()).reshape(len(t), -1).min(axis=1)
        shift = lag + np.asarray(report["te_arcsec"]) / ARCSEC
        assert np.ptp(shift) * ARCSEC < 1e-6
        # at each solved hand-over the two pairs' TE curves meet (bisection to 1e-12 rad)
        assert c.handover_deg.size >= 2
        np.testing.assert_allclose(np.diff(c.handover_deg), math.degrees(curve.pitch), atol=1e-6)
        h = np.radians(c.handover_deg[0])
        mine = curve(np.array([h, h + curve.pitch]))
        candidates = curve(h + ks)
        assert (
            abs(mine[0] - mine[1]) * ARCSEC < 1e-3
            or np.sort(candidates)[1] - np.sort(candidates)[0] < 1e-3 / ARCSEC
        )
        env = c.envelope_arcsec[np.isfinite(c.envelope_arcsec)]
        assert c.peak_to_peak_arcsec == pytest.approx(np.ptp(env))
        assert env.max() == pytest.approx(0.0, abs=0.05 + 0.01 * c.peak_to_peak_arcsec)
        if case["name"] == "section5_3":
            # interior contact at the hand-overs: the TCA's solution and the curves' agree
            assert c.peak_to_peak_arcsec == pytest.approx(
                report["te_peak_to_peak_arcsec"], rel=1e-3
            )
        else:
            # the envelope never lies below the TCA's peak-to-peak (its hand-over under
            # edge contact may take the lower pair's lag: docs/figures.md)
            assert c.peak_to_peak_arcsec <= report["te_peak_to_peak_arcsec"] + 0.01


def test_te_spectrum_holds_the_envelopes_variance(case):
    """Parseval: the harmonics' power is the envelope's variance over a pitch (orders beyond
    the eighth carry little of a TE that is smooth but at the hand-overs)."""
    for c in case["data"]["te"].values():
        t, env = c.t_deg, c.envelope_arcsec
        pitch = float(np.diff(c.handover_deg[:2])[0])
        uniform = c.handover_deg[0] + np.arange(1000) * (pitch / 1000)
        variance = np.var(np.interp(uniform, t, env))  # (the envelope's kinks are sampled)
        power = 0.5 * float(np.sum(c.amplitude_arcsec**2))
        # (a conjugate pair's noise, 1e-3 arcsec, is broadband: an absolute allowance)
        assert power <= 1.02 * variance + 1e-4
        assert power >= 0.9 * variance - 1e-4


def test_te_axes_keep_a_minimum_scale(case):
    ax = case["figures"]["te"].axes[0]
    low, high = ax.get_ylim()
    assert high - low >= MIN_TE_SPAN_ARCSEC
    if case["name"] == "epicycloid":  # conjugate: the noise must not fill the axes
        c = case["data"]["te"]["drive"]
        assert np.ptp(c.envelope_arcsec) < 0.05 * (high - low)


def test_tooth_outlines_are_the_blanks(case):
    blank = case["design"].blank
    width = blank.outer_cone_distance_mm - blank.inner_cone_distance_mm
    for side in ("drive", "coast"):
        for k, m in enumerate(case["data"]["pattern"][side]):
            expected = [
                [0.0, -blank.dedendum_at_mm(k, blank.inner_cone_distance_mm)],
                [width, -blank.dedendum_at_mm(k, blank.outer_cone_distance_mm)],
                [width, blank.addendum_at_mm(k, blank.outer_cone_distance_mm)],
                [0.0, blank.addendum_at_mm(k, blank.inner_cone_distance_mm)],
            ]
            np.testing.assert_allclose(m.outline.corners_mm, expected, atol=1e-9)
            if case["name"] == "tapered":  # the root line falls at the dedendum angle
                c = m.outline.corners_mm
                slope = (c[1, 1] - c[0, 1]) / width
                assert slope == pytest.approx(-math.tan(math.radians(blank.dedendum_angle_deg[k])))
                assert abs(slope) > 1e-3
            # the generated nodes lie on the tooth (their heights between root and face line)
            x, y = m.grid_x_mm[m.generated], m.grid_y_mm[m.generated]
            root = np.interp(x, [0.0, width], m.outline.corners_mm[:2, 1])
            top = np.interp(x, [0.0, width], m.outline.corners_mm[[3, 2], 1])
            assert np.all(y >= root - 0.02) and np.all(y <= top + 0.02)


def test_patterns_lie_on_both_members_teeth_with_m(case):
    tca = case["evaluations"]["tca"]
    blank = case["design"].blank
    for side, key in (("drive", "tca"), ("coast", "tca_coast")):
        pinion, gear = case["data"]["pattern"][side]
        assert (pinion.member, gear.member) == ("pinion", "gear")
        assert pinion.pattern and gear.pattern and pinion.zones and gear.zones
        for m in (pinion, gear):
            c = m.outline.corners_mm
            points = np.vstack(m.pattern + m.zones)
            assert np.all(points[:, 0] >= -0.5) and np.all(points[:, 0] <= c[1, 0] + 0.5)
            assert np.all(points[:, 1] >= c[:2, 1].min() - 0.5)
            assert np.all(points[:, 1] <= c[2:, 1].max() + 0.5)
        # M on the pinion is the reported M (its face coordinate: the same origin, the toe)
        assert pinion.mean_point_mm[0] == pytest.approx(
            tca.report[key]["pattern"]["mean_point_mm"][0]
        )
        # the pinion's M lies in its pattern's extent along the face, and the gear's too
        for m in (pinion, gear):
            xs = np.concatenate([p[:, 0] for p in m.pattern])
            assert xs.min() <= m.mean_point_mm[0] <= xs.max()
        # the pair's contact maps the pinion's face positions to nearly the same gear ones
        # (both measured along the pitch cones from the toe)
        assert abs(gear.mean_point_mm[0] - pinion.mean_point_mm[0]) < 0.1 * blank.face_width_mm


def test_ease_off_has_one_colour_scale(case):
    fig = case["figures"]["ease_off"]
    sets = [ax.collections[0] for ax in fig.axes[:2]]
    assert sets[0].norm.vmin == sets[1].norm.vmin and sets[0].norm.vmax == sets[1].norm.vmax
    report = case["evaluations"]["ease-off"].report["ease_off"]
    assert max(report["drive"]["max_um"], report["coast"]["max_um"]) <= sets[0].norm.vmax + 1e-9
    assert len([ax for ax in fig.axes if ax.get_label() == "<colorbar>"]) == 1


def test_backlash_shows_the_window(case):
    ax = case["figures"]["backlash"].axes[0]
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any("window 150 to 260 um" in t for t in texts)
    low, high = ax.get_ylim()
    assert low <= WINDOW_UM[0] and high >= WINDOW_UM[1]


def test_misalignment_sweep_centre_is_the_analysis():
    """On section 5.3 (one design is enough for the sweep's numbers)."""
    from gearopt.figures.sweep import misalignment_sweep

    design = gearopt.load_design(DESIGNS["section5_3"])
    evaluation = evaluators()["tca"].evaluate(design, {})
    sweep = misalignment_sweep(design, figure_data(design, evaluation)["options"])
    tca = evaluation.report
    for side, key in (("drive", "tca"), ("coast", "tca_coast")):
        for letter in ("V", "H", "J", "Sigma"):
            np.testing.assert_allclose(
                sweep.mean_point_mm[side][letter][1], tca[key]["pattern"]["mean_point_mm"]
            )
        np.testing.assert_allclose(
            sweep.vh_mean_point_mm[side][1, 1], tca[key]["pattern"]["mean_point_mm"]
        )
        # the offset V moves the pattern along the face, monotonically (seed 001's pair is
        # sensitive: millimetres per 0.1 mm)
        face = sweep.mean_point_mm[side]["V"][:, 0]
        assert np.all(np.diff(face) > 0.5) or np.all(np.diff(face) < -0.5)


class _Page(HTMLParser):
    def __init__(self):
        super().__init__()
        self.images, self.figures, self.external = [], [], []

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == "img":
            self.images.append(attrs)
        if tag == "figure":
            self.figures.append(attrs.get("id"))
        for key in ("src", "href"):
            if key in attrs and not attrs[key].startswith("data:"):
                self.external.append(attrs[key])


def test_report_writes_one_self_contained_page(tmp_path, capsys):
    args = ["report", str(DESIGNS["section5_3"]), "--out", str(tmp_path)]
    assert main([*args, "--backlash-window-um", "150,260"]) == 0
    pages = list(tmp_path.glob("*.html"))
    assert [p.name for p in pages] == ["seed001_section5_3.html"]
    text = pages[0].read_text()
    page = _Page()
    page.feed(text)
    assert page.external == []
    assert {"fig-te", "fig-pattern", "fig-ease_off", "fig-backlash", "fig-misalignment"} <= set(
        page.figures
    )
    for image in page.images:
        head, data = image["src"].split(",", 1)
        assert head == "data:image/png;base64"
        assert base64.b64decode(data)[:8] == b"\x89PNG\r\n\x1a\n"
    assert "te_peak_to_peak_arcsec" in text and "inner_cutter_radius_mm" in text
    assert "backlash window_um" in text and "outer_cone_distance_mm" in text


def test_report_bad_window_is_one_line(capsys, tmp_path):
    args = ["report", str(DESIGNS["section5_3"]), "--out", str(tmp_path)]
    assert main([*args, "--backlash-window-um", "260,150"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "backlash-window-um" in err[0]
