"""``fitbench list``: one line per registered method (id, kind and its one-line summary: what it computes and
minimises), with ``--long`` its reference under it, or the listing with defaults as JSON."""
from __future__ import annotations

import json

import fitbench.cli.options as cli_options
from fitbench.cli.guards import jsonable


def add_parser(sub):
    pl = sub.add_parser("list", help="one line per registered method: id, kind and what it computes (--long: "
                                     "and its reference)")
    pl.add_argument("--family", help="only this family (e.g. circle)")
    pl.add_argument("--long", action="store_true", help="also each method's literature reference, under its line")
    pl.add_argument("--json", action="store_true", help="machine-readable listing with defaults")
    pl.set_defaults(func=run)


def run(args) -> int:
    from methods import describe_methods  # the built-in methods without importing their families

    specs = describe_methods(args.family)
    if not specs and args.family is not None:
        from methods import InvalidInputError
        families = sorted({s.family for s in describe_methods()})
        raise InvalidInputError(f"no family {args.family!r}; the families: {', '.join(families)}")
    if args.json:
        cli_options.print_json(json.dumps([{"id": s.id, "family": s.family, "kind": s.kind, "summary": s.summary,
                           "reference": s.reference, "defaults": {k: jsonable(v) for k, v in s.defaults.items()}}
                          for s in specs], indent=1))
        return 0
    width = max((len(s.id) for s in specs), default=10)
    for s in specs:
        # the summary says what a method minimises (kasa, pratt, taubin, hyper: algebraic; powell_hybrid: Kåsa's
        # objective; chebyshev_lp: an algebraic Chebyshev fit), which a citation alone does not
        print(f"{s.id:<{width}}  {s.kind:<14}  {' '.join(str(s.summary or '-').split())}")
        if args.long:
            print(f"{'':<{width}}  {'':<14}  reference: {s.reference or '-'}")
    return 0
