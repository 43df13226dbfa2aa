"""The roundness polar plot labels the ring of the reference radius '0 µm', as the circular-test plot does (it read
'+0 µm'); the other rings keep their sign."""
import re

import numpy as np

import methods
from fitbench.plots import pyplot
from fitbench.plots.roundness import plot


def test_the_reference_ring_reads_0_um():
    t = np.linspace(0, 2 * np.pi, 720, endpoint=False)
    r = 10 + 0.002 * np.cos(3 * t) + 0.001 * np.sin(5 * t)
    res = methods.fit("roundness.iso12181", np.c_[r * np.cos(t), r * np.sin(t)], cutoff_upr=50.0)
    fig = pyplot().figure()
    try:
        plot(res, None, into=fig)
        labels = [tl.get_text() for tl in fig.axes[0].get_yticklabels()]
    finally:
        pyplot().close(fig)
    assert "0 µm" in labels, labels
    assert not [s for s in labels if re.fullmatch(r"[+-]0(\.0*)? µm", s)], labels
    assert all(re.fullmatch(r"[+-]\d+(\.\d+)? µm", s) for s in labels if s != "0 µm"), labels
