"""Controller compensation tables (fitbench.compensation) and the ``fitbench positioning --compensation`` door."""
from __future__ import annotations

import contextlib
import io
from types import SimpleNamespace

import numpy as np
import pandas as pd

import methods
from datasets.positioning import axis_test, to_frame
from fitbench.cli import main
from fitbench.compensation import compensation_table
from methods.positioning.model import evaluate_band


def cli(*args):
    """``fitbench ARGS`` in this process."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main([str(a) for a in args])
    return SimpleNamespace(returncode=code, stdout=out.getvalue(), stderr=err.getvalue())


def test_compensation_tables(tmp_path):
    data, _ = axis_test(rng=np.random.default_rng(2), mpe=0.002)
    to_frame(data, actual=False).to_csv(tmp_path / "a.csv", index=False)
    out = cli("positioning", tmp_path / "a.csv", "--mpe", 0.002, "--interval", 25, "--compensation", "csv",
              tmp_path / "c.csv", "--compensation", "siemens-eec", tmp_path / "eec.mpf", "--compensation", "fanuc-pitch",
              tmp_path / "f.txt")
    assert out.returncode == 0, out.stderr
    res = methods.fit("positioning.gls_polynomial", data, mpe=0.002)
    pos = np.arange(0, 1000.0 + 1e-9, 25.0)
    want = -0.5 * (evaluate_band(res.polynomial["up"], pos)[0] + evaluate_band(res.polynomial["down"], pos)[0])
    csv = pd.read_csv(tmp_path / "c.csv", comment="#")
    np.testing.assert_allclose(csv.position_mm, pos)
    np.testing.assert_allclose(csv.compensation_mm, want, atol=1e-6)
    eec = (tmp_path / "eec.mpf").read_text().splitlines()
    assert eec[0] == "%_N_AX_EEC_INI" and eec[-1] == "M17" and "CHANDATA(1)" in eec
    vals = [float(l.split("=")[1]) for l in eec if l.startswith("$AA_ENC_COMP[0,")]
    np.testing.assert_allclose(vals, want, atol=1e-6)
    assert "$AA_ENC_COMP_STEP[0,X1]=25.000000" in eec and "$AA_ENC_COMP_MAX[0,X1]=1000.000000" in eec
    fanuc = (tmp_path / "f.txt").read_text().splitlines()
    inc = [int(l.split("P")[1]) for l in fanuc if l.startswith("N1")]
    assert len(inc) == len(pos) and inc[0] == 0
    np.testing.assert_allclose(np.cumsum(inc) * 1e-3, want - want[0], atol=0.5e-3 + 1e-12)  # 1 µm detection unit
    mean = compensation_table(res, data, interval=100.0, source="mean")
    np.testing.assert_allclose(mean.compensation_mm, -res.per_target["mean_bidirectional"], atol=1e-12)


def test_methods_does_not_import_the_controller_export():
    """Layers run one way: the algorithms never import the fitbench layer's controller export."""
    import pathlib
    root = pathlib.Path(methods.__file__).parent
    offenders = [str(p.relative_to(root)) for p in root.rglob("*.py") if "compensation" in p.read_text()
                 and ("fitbench.compensation" in p.read_text() or "import compensation" in p.read_text())]
    assert offenders == []
    assert not (root / "positioning" / "compensation.py").exists()
