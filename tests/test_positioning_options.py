"""``fitbench positioning``'s instrument options: ``--mpe`` / ``--instrument-u`` take a unit (a bare number is mm, as
before), and a bare number larger than every deviation of the axis is warned about, naming the likely unit (the
operator's "2 µm laser" given as ``--mpe 2`` used to give U = 2309 µm silently)."""
import json

import numpy as np
import pytest

from fitbench.cli import main
from positioning_tables import axis_csv


@pytest.fixture(scope="module")
def axis_file(tmp_path_factory):
    path, data = axis_csv(tmp_path_factory.mktemp("pos"))
    largest = max(np.abs(data.up).max(), np.abs(data.down).max())
    return str(path), largest


def run(capsys, *args):
    code = main(["positioning", *map(str, args)])
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.mark.parametrize("option, bare, unit", [("--mpe", "2", "2um"), ("--instrument-u", "1", "1um")])
def test_a_bare_number_above_every_deviation_is_warned_naming_the_unit(axis_file, capsys, option, bare, unit):
    path, largest = axis_file
    code, out, err = run(capsys, path, option, bare)
    assert code == 0
    assert (f"warning: {option} {bare} is read as {bare} mm (a bare number is mm), larger than every deviation of this "
            f"axis (largest |deviation| {largest * 1e3:.3g} µm): is it in µm? give {option} {unit}") in err
    code, out, err = run(capsys, path, option, unit)
    assert code == 0 and "warning" not in err
    code, out, err = run(capsys, path, option, f"{bare}mm")            # said in mm: meant, no warning
    assert code == 0 and "warning" not in err


def test_a_unit_suffix_gives_the_same_model_as_mm(axis_file, capsys):
    path, _ = axis_file
    got = {}
    for text in ("0.002", "2um", "2 µm", "2000nm", "0.002mm"):
        code, out, err = run(capsys, path, "--mpe", text, "--json")
        assert code == 0 and "warning" not in err, err
        got[text] = json.loads(out)
    for text, d in got.items():
        assert d["u_delta"] == pytest.approx(0.002 / np.sqrt(3), rel=1e-12), text
        assert d["polynomial"] == got["0.002"]["polynomial"], text
    code, out, err = run(capsys, path, "--instrument-u", "500nm", "--json")
    assert code == 0 and json.loads(out)["u_delta"] == pytest.approx(0.0005, rel=1e-12)


@pytest.mark.parametrize("text, match", [("2cm", "--mpe '2cm': unknown unit 'cm'; use um"),
                                         ("two", "--mpe 'two': give a length with its unit, e.g. --mpe 2um")])
def test_a_bad_instrument_length_is_one_line(axis_file, capsys, text, match):
    code, out, err = run(capsys, axis_file[0], "--mpe", text)
    assert code == 2 and match in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_the_help_states_the_units(capsys):
    with pytest.raises(SystemExit):
        main(["positioning", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    for option in ("--mpe MPE", "--instrument-u U"):
        i = text.index(option, text.index("options:"))
        assert "a bare number is mm (unlike --tolerance, in µm)" in text[i:i + 260], option
    assert "a tolerance in µm" in text
