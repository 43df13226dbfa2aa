"""The magnified-trajectory figure (experiments.studies.magnification.trajectories_figure): a panel with a
zoom box shows exactly that box at equal x/y scales, without matplotlib's "Ignoring fixed x/y limits to
fulfill fixed data aspect" warnings (the cause: equal aspect with adjustable data limits over fixed limits)."""
import logging

import pytest

from experiments import config as configs
from experiments.render import style
from experiments.studies import magnification


class _Records(logging.Handler):
    def __init__(self):
        super().__init__(logging.WARNING)
        self.records = []

    def emit(self, record):
        self.records.append(record)


@pytest.fixture(scope="module")
def drawn(tmp_path_factory):
    """Draw the study's own panels once for this file's tests (the figure is only read); keep the figure that
    style.save writes (and closes) and matplotlib's warnings logged while drawing."""
    kept, records, logger = [], _Records(), logging.getLogger("matplotlib")
    save = style.save
    target = tmp_path_factory.mktemp("magnification") / "magnification.png"
    cfg = configs.load("magnification", quick=True)
    cfg["examples"] = {name: 200.0 for name in cfg["examples"]}
    panels = magnification._panels(cfg)
    level = logger.level
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(style, "save", lambda fig, path, **kw: (kept.append(fig), save(fig, path, **kw))[1])
        logger.addHandler(records)
        logger.setLevel(logging.WARNING)
        try:
            magnification.trajectories_figure(panels, target)
        finally:
            logger.removeHandler(records)
            logger.setLevel(level)
    assert target.stat().st_size > 10_000
    return panels, kept[0], records.records


def test_no_aspect_warning(drawn):
    _, _, records = drawn
    assert not [r.getMessage() for r in records if "Ignoring fixed" in r.getMessage()]


def test_zoom_box_shown_exactly_at_equal_scales(drawn):
    panels, fig, _ = drawn
    boxed = [(ax, p["box"]) for ax, p in zip(fig.axes, panels) if p.get("box")]
    assert boxed, "the study declares at least one zoom box"
    for ax, (x0, x1, y0, y1) in boxed:
        assert ax.get_xlim() == pytest.approx((x0, x1), abs=1e-12)
        assert ax.get_ylim() == pytest.approx((y0, y1), abs=1e-12)
    for ax in fig.axes[:len(panels)]:
        # equal scales: one mm on x is as long on the page as one mm on y
        bbox = ax.get_window_extent()
        (xa, xb), (ya, yb) = ax.get_xlim(), ax.get_ylim()
        assert (bbox.width / (xb - xa)) == pytest.approx(bbox.height / (yb - ya), rel=1e-3)
