"""``fitbench history DIR``: the trend of one machine's tests over time, from the JSON results that
``fitbench circular-test|positioning|roundness --json`` printed (saved as ``*.json`` in DIR): a table per test
of G, the diagnostics, A/E/R/B and RONt against the date, and optionally a plot (what ballbar users compare
between services). The date of a result is its test conditions' date (``--date``) when given, else the
file's modification time. A trend is one machine's (``--machine``) and, for a circular test, one plane's, for a
positioning test one axis' (``--axis``): results of different machines, planes or axes in one folder are separate
trends (pooled, an X axis and a Y axis of two machines read as one axis drifting). Results evaluated with
different settings (:func:`settings_of`: a positioning test's standard and k or its temperature correction, a
roundness filter's cut-off, a circular test's radius and feed) are separate trends too, named by the setting that
differs, and a warning says so: pooled, k = 3 beside k = 2 read as R growing 24 % on the same data."""
from __future__ import annotations

import fitbench.cli.options as cli_options
from fitbench.cli.guards import check_outputs, written_files

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


#: what separates one trend from another besides the test and the machine: (key in the JSON trend, conditions key)
SERIES = {"circular-test": ("plane", "plane"), "positioning": ("axis", "axis"), "roundness": None}


def series_of(kind: str, d: dict) -> tuple:
    """(test, machine, plane or axis) of the result ``d``: its trend; '' where the result does not say (no machine
    given, a positioning result written before the axis was recorded)."""
    details = d.get("details")
    cond = details.get("conditions") if isinstance(details, dict) else None
    cond = cond if isinstance(cond, dict) else {}
    extra = SERIES[kind]
    where = cond.get(extra[1]) if extra else ""
    return kind, str(cond.get("machine") or "").strip(), str(where or "").strip()


def _number(v) -> float | None:
    return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else None


def settings_of(kind: str, d: dict) -> tuple:
    """((setting, value as text), ...) of the result ``d``: how it was evaluated where that changes the trended
    figures, so that results differing in one are never one trend. Positioning: the standard with its coverage
    factor (ISO 230-2:1988's k = 3 against 2014's k = 2 changes A and R) and whether the deviations were corrected
    to 20 °C; roundness: the Gaussian filter's cut-off (ISO 16610-21; 15 against 50 UPR changes every RON figure);
    circular test: the nominal radius and the feed (ISO 230-4 compares tests at the same radius and feed)."""
    if kind == "positioning":
        k = _number(d.get("k"))
        standard = str(d.get("standard") or "not recorded") + (f" (k = {k:g})" if k is not None else "")
        deviations = "corrected to 20 °C" if d.get("temperature_correction") else "as measured"
        return (("standard", standard), ("deviations", deviations))
    if kind == "roundness":
        cut = _number(d.get("cutoff_upr"))
        return (("filter", "not recorded" if "cutoff_upr" not in d else f"{cut:g} UPR" if cut is not None
                 else "unfiltered"),)
    if kind == "circular-test":
        details = d.get("details")
        cond = details.get("conditions") if isinstance(details, dict) else None
        cond = cond if isinstance(cond, dict) else {}
        radius, feed = _number(cond.get("nominal_radius_mm")), _number(cond.get("feed_mm_min"))
        return (("radius", "not recorded" if radius is None else f"{radius:g} mm"),
                ("feed", "not given" if feed is None else f"{feed:g} mm/min"))
    return ()


def differing(history: dict) -> dict:
    """{(test, machine, plane or axis): [names of the settings that differ between its trends]} for the results
    of one machine's plane or axis that :func:`settings_of` split into several trends."""
    groups: dict = {}
    for key in history:
        if isinstance(key, tuple) and len(key) == 4:
            groups.setdefault(key[:3], []).append(dict(key[3]))
    return {g: [n for n in sets[0] if len({s.get(n) for s in sets}) > 1]
            for g, sets in groups.items() if len(sets) > 1}


def series_title(key, differ: dict | None = None) -> str:
    """The trend's name: e.g. positioning, machine M2, axis Y (a plain test name: that test), with the settings
    that tell it from the plane's or axis' other trends (``differ``: :func:`differing`)."""
    if not isinstance(key, tuple):
        return key
    kind, machine, where = key[:3]
    extra = SERIES.get(kind)
    title = f"{kind}, machine {machine or 'not given'}" + (f", {extra[0]} {where or 'not recorded'}" if extra else "")
    names = (differ or {}).get(key[:3], [])
    settings = dict(key[3]) if len(key) == 4 else {}
    return title + "".join(f", {n} {settings[n]}" for n in names if n in settings)


def mixed_settings_warnings(history: dict) -> list[str]:
    """One line per machine's plane or axis whose results were evaluated with different settings: which differ,
    and that they are separate trends."""
    out = []
    differ = differing(history)
    for group, names in differ.items():
        sets = [dict(k[3]) for k in history if isinstance(k, tuple) and len(k) == 4 and k[:3] == group]
        what = "; ".join(f"{n} {' / '.join(dict.fromkeys(s[n] for s in sets))}" for n in names)
        out.append(f"{series_title(group)}: the results were evaluated with different settings ({what}); their "
                   "figures are not comparable: shown as separate trends")
    return out


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
    """{(test, machine, plane or axis, settings): [(date, file, {column: value})]} (:func:`series_of`,
    :func:`settings_of`; one trend each) from
    the JSON results in ``folder``, oldest first, the trends ordered by test, machine, plane or axis. A ``*.json``
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
        out.setdefault((*series_of(kind, d), settings_of(kind, d)), []).append((date, path.name, row))
    if not out:
        raise InvalidInputError(f"{folder}: no JSON results of circular-test, positioning or roundness found "
                                "(save them with: fitbench circular-test ... --json > DIR/2026-11-25.json)")
    order = {k: i for i, k in enumerate(COLUMNS)}
    # one machine's plane or axis evaluated with several settings: its trends by their first test's date
    keys = sorted(out, key=lambda k: (order[k[0]], k[1], k[2], min((r[0], r[1]) for r in out[k])))
    return {k: sorted(out[k], key=lambda r: (r[0], r[1])) for k in keys}


def _kind(key) -> str:
    """The test of a trend's key (a plain test name is one trend of that test)."""
    return key[0] if isinstance(key, tuple) else key


def table(history: dict) -> str:
    lines = []
    differ = differing(history)
    for key, rows in history.items():
        cols = COLUMNS[_kind(key)]
        lines.append(f"{series_title(key, differ)}: {len(rows)} test(s)")
        head = f"  {'date':<16} {'file':<28} " + " ".join(f"{f'{n} [{u}]':>18}" for _, n, _, u in cols)
        lines += [head, "  " + "-" * (len(head) - 2)]
        for date, name, row in rows:
            lines.append(f"  {date:%Y-%m-%d %H:%M} {name[:28]:<28} " +
                         " ".join(f"{'-' if row[n] is None else f'{row[n]:.3f}':>18}" for _, n, _, _ in cols))
        lines.append("")
    return "\n".join(lines).rstrip()


def as_json(history: dict) -> dict:
    """{test: {units, trends: [{machine, plane or axis, settings, tests}], tests: every test of it (each with its
    machine, plane or axis and settings), by date}}, the values in the printed units."""
    out: dict = {}
    for key, rows in history.items():
        kind, machine, where = key[:3] if isinstance(key, tuple) else (key, "", "")
        extra = SERIES.get(kind)
        labels = {"machine": machine, **({extra[0]: where} if extra else {})}
        if isinstance(key, tuple) and len(key) == 4:
            labels["settings"] = dict(key[3])
        tests = [{"date": d.isoformat(timespec="minutes"), "file": f, **labels, **row} for d, f, row in rows]
        entry = out.setdefault(kind, {"units": {n: u for _, n, _, u in COLUMNS[kind]}, "trends": [], "tests": []})
        entry["trends"].append({**labels, "tests": tests})
        entry["tests"].extend(tests)
    for entry in out.values():
        entry["tests"].sort(key=lambda t: (t["date"], t["file"]))
    return out


def plot(history: dict, path, save) -> None:
    """The trend plot (:func:`fitbench.plots.history.plot`)."""
    from fitbench.plots.history import plot as draw
    differ = differing(history)
    draw(history, COLUMNS, path, save, titles={k: series_title(k, differ) for k in history})


def add_parser(sub):
    p = sub.add_parser("history", help="trends of each machine's tests (per plane or axis) over time from their "
                                       "saved --json results")
    p.add_argument("folder", metavar="DIR", help="folder of JSON results (fitbench circular-test|positioning|roundness --json)")
    p.add_argument("--json", action="store_true", help="print the trends as one JSON object (values in the printed "
                   "units; per test its 'trends', one per machine and plane or axis, and all its 'tests'; "
                   "'files_written': the --plot written, as every command's JSON lists its files)")
    p.add_argument("--plot", metavar="FILE", help="write the trend plot (.png, .pdf, .svg)")
    p.set_defaults(func=run)
    return p


def run(args) -> int:
    plot_path = check_plot_path(args.plot)
    check_outputs([args.folder], [("--plot", args.plot, "plot")])
    history = collect(args.folder)
    for line in mixed_settings_warnings(history):
        _warn(line)
    if plot_path:
        plot(history, plot_path, save_figure)
    if args.json:   # the trends by test, and the files written (as every command's JSON lists them)
        cli_options.print_json(json.dumps({**as_json(history), "files_written": written_files()}))
        return 0
    print(table(history))
    return 0
