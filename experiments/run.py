"""``python -m experiments.run [NAME ...] [--list] [--out DIR]``: run studies, write results/.

Each study writes ``OUT/NAME/results.csv`` (long format, one row per data set x method run; timing
columns start with ``time_``) and ``OUT/NAME/meta.json`` (provenance and study-level findings),
both atomically. No NAME runs the default studies.
"""
from __future__ import annotations

import argparse
import importlib
import io
import json
import sys
from pathlib import Path

import pandas as pd

from experiments import config as configs
from experiments.provenance import REPO, collect, write_atomic
from methods import InvalidInputError


def default_studies() -> list[str]:
    return [n for n in configs.available() if configs.load(n).get("default", False)]


def run_study(name: str, out: Path, log=print) -> Path:
    cfg = configs.load(name)
    study = importlib.import_module(f"experiments.studies.{cfg['kind']}")
    log(f"== {name}: {cfg['title']}")
    rows, findings = study.run(cfg, log=log)
    public_cfg = {k: v for k, v in cfg.items() if not k.startswith("_")}
    meta = {**collect(public_cfg), "study": name, "n_rows": len(rows), "findings": findings}
    target = out / name
    buf = io.StringIO()
    pd.DataFrame(rows).to_csv(buf, index=False, float_format="%.17g")
    write_atomic(target / "results.csv", buf.getvalue())
    write_atomic(target / "meta.json", json.dumps(meta, indent=1, default=str) + "\n")
    if hasattr(study, "figure"):
        study.figure(rows, findings, target)
    log(f"-> {target / 'results.csv'} ({len(rows)} rows), {target / 'meta.json'}")
    return target


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m experiments.run", description=__doc__.splitlines()[0])
    parser.add_argument("names", nargs="*", metavar="NAME", help="studies to run (default: the default studies)")
    parser.add_argument("--list", action="store_true", help="list the studies, one line each")
    parser.add_argument("--out", type=Path, default=REPO / "results", help="output directory (default: results/)")
    args = parser.parse_args(argv)
    try:
        if args.list:
            for name in configs.available():
                cfg = configs.load(name)
                print(f"{name:<22} {'default' if cfg.get('default') else '       '}  {cfg['title']}")
            return 0
        for name in args.names or default_studies():
            run_study(name, args.out)
    except InvalidInputError as exc:
        print(f"experiments.run: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("experiments.run: interrupted; finished studies are written, rerun to redo the others", file=sys.stderr)
        return 130
    return 0


if __name__ == "__main__":
    sys.exit(main())
