"""``fitbench history DIR``: the trend of one machine's tests over time, from the JSON results that
``fitbench circular-test|positioning|roundness --json`` printed (saved as ``*.json`` in DIR): a table per test
of G, the diagnostics, A/E/R/B and RONt against the date, and optionally a plot (what ballbar users compare
between services). The date of a result is its test conditions' date (``--date``) when given, else the
file's modification time."""
from __future__ import annotations

import datetime as _dt
import json
from pathlib import Path

from methods import InvalidInputError
from methods.files import open_regular
from fitbench.cli.options import DATE_FORMATS, check_plot_path, save_figure, warn as _warn

#: the columns of each test's trend: (JSON path, printed name, factor to the printed unit, unit)
COLUMNS = {
    "circular-test": [(("G_b",), "G(b)", 1e3, "µm"), (("G_cw",), "G CW", 1e3, "µm"), (("G_ccw",), "G CCW", 1e3, "µm"),
                      (("diagnostics", "squareness", "value"), "squareness", 1e6, "µrad"),
                      (("diagnostics", "scale_mismatch", "value"), "scale mismatch", 1e6, "µm/m"),
                      (("diagnostics", "backlash_x", "value"), "backlash X", 1e3, "µm"),
                      (("diagnostics", "backlash_y", "value"), "backlash Y", 1e3, "µm"),
                      (("diagnostics", "servo_mismatch", "value@mm"), "servo mismatch", 1e3, "µm"),
                      (("diagnostics", "servo_mismatch", "value@s"), "servo mismatch (time)", 1e3, "ms")],
    "positioning": [(("A",), "A", 1e3, "µm"), (("E",), "E", 1e3, "µm"), (("R",), "R", 1e3, "µm"),
                    (("B",), "B", 1e3, "µm"), (("M",), "M", 1e3, "µm")],
    "roundness": [(("references", "lsci", "RONt"), "RONt LSCI", 1e3, "µm"),
                  (("references", "mzci", "RONt"), "RONt MZCI", 1e3, "µm"),
                  (("references", "mici", "RONt"), "RONt MICI", 1e3, "µm"),
                  (("references", "mcci", "RONt"), "RONt MCCI", 1e3, "µm")],
}


def kind_of(d: dict) -> str | None:
    """Which command printed the JSON object ``d`` (by its keys), None for another JSON."""
    if "G_b" in d and "diagnostics" in d:
        return "circular-test"
    if "per_target" in d and "A" in d:
        return "positioning"
    if "references" in d and "raw_lsci" in d:
        return "roundness"
    return None


def _get(d, path):
    """The number at ``path``; a last key ``value@UNIT`` takes the value only where the entry's JSON unit is
    UNIT (the servo mismatch is a length without the feed and a time with it)."""
    *head, last = path
    key, _, unit = last.partition("@")
    for k in head:
        if not isinstance(d, dict) or k not in d:
            return None
        d = d[k]
    if not isinstance(d, dict) or key not in d or (unit and d.get("unit") != unit):
        return None
    d = d[key]
    return d if isinstance(d, (int, float)) and not isinstance(d, bool) else None


def _date(d: dict, path: Path) -> _dt.datetime:
    """The test's date: its conditions' ``date`` (:data:`DATE_FORMATS`), else the file's modification time; a
    date that is not one is an :class:`~methods.InvalidInputError` naming the file."""
    details = d.get("details")
    conditions = details.get("conditions") if isinstance(details, dict) else None
    text = conditions.get("date") if isinstance(conditions, dict) else None
    if text:
        for fmt in DATE_FORMATS:
            try:
                return _dt.datetime.strptime(str(text).strip(), fmt)
            except ValueError:
                pass
        raise InvalidInputError(f"{path}: test date {text!r} is not a date (use YYYY-MM-DD)")
    return _dt.datetime.fromtimestamp(path.stat().st_mtime)


def _load(path: Path):
    """The JSON value in ``path`` (any size: a roundness result is one line of 100 kB and more), or an
    :class:`~methods.InvalidInputError` saying why it cannot be read (a FIFO or a device is refused unopened)."""
    try:
        with open_regular(path, encoding="utf-8-sig") as fh:
            return json.load(fh)
    except InvalidInputError:
        raise
    except OSError as exc:
        raise InvalidInputError(f"{path}: cannot be read ({exc.strerror or exc})") from None
    except UnicodeDecodeError:
        raise InvalidInputError(f"{path}: not UTF-8 text") from None
    except (ValueError, RecursionError) as exc:
        raise InvalidInputError(f"{path}: not valid JSON ({str(exc).splitlines()[0][:120]})") from None


def collect(folder, warn=None) -> dict:
    """{test: [(date, file, {column: value})]} from the JSON results in ``folder``, oldest first. A ``*.json``
    that is not a result (unreadable, not JSON, another JSON, a test date that is not a date) is skipped and
    told to ``warn`` (a function taking one line; default :func:`fitbench.cli.options.warn`)."""
    warn = warn or _warn
    folder = Path(folder)
    if not folder.is_dir():
        raise InvalidInputError(f"{folder}: not a folder; give the folder holding the tests' JSON results")
    out: dict = {}
    for path in sorted(folder.rglob("*.json")):
        try:
            d = _load(path)
            kind = kind_of(d) if isinstance(d, dict) else None
            if kind is None:
                raise InvalidInputError(f"{path}: not a JSON result of circular-test, positioning or roundness")
            date = _date(d, path)
        except InvalidInputError as exc:
            warn(f"{exc}; skipped")
            continue
        row = {name: (None if (v := _get(d, p)) is None else v * f) for p, name, f, _ in COLUMNS[kind]}
        out.setdefault(kind, []).append((date, path.name, row))
    if not out:
        raise InvalidInputError(f"{folder}: no JSON results of circular-test, positioning or roundness found "
                                "(save them with: fitbench circular-test ... --json > DIR/2026-11-25.json)")
    return {k: sorted(v, key=lambda r: (r[0], r[1])) for k, v in out.items()}


def table(history: dict) -> str:
    lines = []
    for kind, rows in history.items():
        cols = COLUMNS[kind]
        lines.append(f"{kind}: {len(rows)} test(s)")
        head = f"  {'date':<16} {'file':<28} " + " ".join(f"{f'{n} [{u}]':>18}" for _, n, _, u in cols)
        lines += [head, "  " + "-" * (len(head) - 2)]
        for date, name, row in rows:
            lines.append(f"  {date:%Y-%m-%d %H:%M} {name[:28]:<28} " +
                         " ".join(f"{'-' if row[n] is None else f'{row[n]:.3f}':>18}" for _, n, _, _ in cols))
        lines.append("")
    return "\n".join(lines).rstrip()


def plot(history: dict, path, save) -> None:
    """The trend plot (:func:`fitbench.plots.history.plot`)."""
    from fitbench.plots.history import plot as draw
    draw(history, COLUMNS, path, save)


def add_parser(sub):
    p = sub.add_parser("history", help="trend of one machine's tests over time from their saved --json results")
    p.add_argument("folder", metavar="DIR", help="folder of JSON results (fitbench circular-test|positioning|roundness --json)")
    p.add_argument("--json", action="store_true", help="print the trend as one JSON object (values in the printed units)")
    p.add_argument("--plot", metavar="FILE", help="write the trend plot (.png, .pdf, .svg)")
    p.set_defaults(func=run)
    return p


def run(args) -> int:
    plot_path = check_plot_path(args.plot)
    history = collect(args.folder)
    if plot_path:
        plot(history, plot_path, save_figure)
    if args.json:
        print(json.dumps({kind: {"units": {n: u for _, n, _, u in COLUMNS[kind]},
                                 "tests": [{"date": d.isoformat(timespec="minutes"), "file": f, **row}
                                           for d, f, row in rows]} for kind, rows in history.items()}))
        return 0
    print(table(history))
    return 0
