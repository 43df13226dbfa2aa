"""Study configs: one TOML file per study in ``experiments/configs/`` (or any path), validated on load."""
from __future__ import annotations

import os
import tomllib
from pathlib import Path

from experiments import engine, schema
from experiments.declarations import validate as validate_declarations
from experiments.study import ConfigError, count_rows, study_of  # noqa: F401  (count_rows: API)

CONFIG_DIR = Path(__file__).resolve().parent / "configs"


class StudyConfig(dict):
    """A study's config, checked once when loaded (:func:`load`): the TOML's keys as a mapping (what ``meta.json``
    records and the study reads), and where it came from as typed attributes, never as keys of the mapping.

    ``where``: the file name that errors name; ``folder``: the TOML's folder (``file = ...`` data sets are
    relative to it); ``quick``: whether its ``[quick]`` table was applied; ``file``: the TOML file as it was given
    (its folder resolved, a link kept as the link: what ``meta.json`` records and a rerun loads), None when the
    config was made in memory."""

    where: str
    folder: Path
    quick: bool
    file: Path | None

    def __init__(self, values: dict, *, where: str, folder: Path, quick: bool = False, file: Path | None = None):
        super().__init__(values)
        self.where, self.folder, self.quick = str(where), Path(folder), bool(quick)
        self.file = None if file is None else Path(file)

    def replace(self, **changes) -> "StudyConfig":
        """A copy with some keys changed (the same origin)."""
        return StudyConfig({**self, **changes}, where=self.where, folder=self.folder, quick=self.quick, file=self.file)

    # -- its expansion (``experiments.engine``), for a study's ``validate`` and ``tasks``: a study module names the
    # engine through its config, never by an import, so that its rows' cache keys hold no library of the run's own
    # (the progress bars, Dask, the report's templates: docs/studies.md)

    def expand_datasets(self) -> list[dict]:
        """Its data set specs, one per grid point of each ``[[datasets]]`` entry (``experiments.engine.expand_datasets``)."""
        return engine.expand_datasets(self, self.where)

    def expand_methods(self) -> list[tuple[str, dict]]:
        """(method id, its ``params``, ``on``, ``max_n``) per grid point of each ``[[methods]]`` entry
        (``experiments.engine.expand_methods``; ``family.*`` expanded)."""
        return engine.expand_methods(self, self.where)

    def grid_tasks(self, *, keyed: bool = False):
        """The generic grid's tasks, lazily: data sets x repetitions x methods (``experiments.engine.iter_grid_tasks``);
        ``keyed``: each with its index and cache key."""
        return engine.iter_grid_tasks(self, self.where, keyed=keyed)

    def prepare(self, tasks):
        """A study's own tasks with their index and cache key, lazily (``experiments.engine.iter_prepared``)."""
        return engine.iter_prepared(tasks)

    def __reduce__(self):  # pickled with its attributes (a plain dict's pickle would drop them)
        return (_study_config, (dict(self), self.where, str(self.folder), self.quick,
                                None if self.file is None else str(self.file)))


def _study_config(values, where, folder, quick, file=None):
    return StudyConfig(values, where=where, folder=Path(folder), quick=quick, file=file)


def available() -> dict[str, Path]:
    return {p.stem: p for p in sorted(CONFIG_DIR.glob("*.toml"))}


#: The largest grid a run expands without ``--max-rows`` (each row is one fit; 10^6 rows is hours of work).
MAX_ROWS = 1_000_000


def _read(path: Path, where: str) -> dict:
    if path.is_dir():
        raise ConfigError(f"{where}: is a directory, not a TOML file")
    try:
        text = path.read_bytes().decode("utf-8-sig")   # a byte-order mark (Windows editors' "UTF-8 with BOM") is no TOML
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{where}: not UTF-8 text (byte {exc.start}); save the config as UTF-8") from None
    except OSError as exc:
        raise ConfigError(f"{where}: cannot be read ({exc.strerror})") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{where}: not valid TOML ({exc})") from None


def _study(cfg: dict, where: str):
    """The :class:`experiments.study.Study` of the config's kind (None while ``kind`` is not a string: the
    structure check then says so); it declares the study's own config keys (``config_schema``)."""
    kind = cfg.get("kind", "grid")
    if not isinstance(kind, str):
        return None
    try:
        return study_of(kind)
    except ConfigError as exc:
        raise ConfigError(f"{where}: {exc}") from None


def load(name: str, *, quick: bool = False, seed: int | None = None) -> StudyConfig:
    """The config of study ``name`` (or of a .toml path), with its ``[quick]`` table applied when
    ``quick`` and ``seed`` overriding its seed. Everything is checked before a row runs: the structure
    (experiments/schema.py), the values of data-source and method parameters, the study's own rules.
    Errors name the file, the key and the problem in one line."""
    path = Path(name)
    if path.suffix == ".toml" and path.exists():
        stem = path.stem
    else:
        configs = available()
        if name not in configs and (path.suffix == ".toml" or "/" in name or os.sep in name):
            if path.exists():
                raise ConfigError(f"{name}: not a .toml file; a study config is a TOML file named NAME.toml")
            hint = (f"; the built-in study {path.stem!r} is run by its name: python -m experiments.run {path.stem}"
                    if path.stem in configs else "")
            raise ConfigError(f"no such file: {name}{hint}")
        if name not in configs:
            raise ConfigError(f"unknown study {name!r}; 'python -m experiments.run --list' shows them "
                              f"({', '.join(configs) or 'none'})")
        path, stem = configs[name], name
    where = path.name
    cfg = _read(path, where)
    study = _study(cfg, where)
    schema.check_structure(cfg, where, study.config_schema if study else None)
    cfg.setdefault("kind", "grid")  # no kind: the generic benchmark (the base Study)
    if cfg["name"] != stem:
        raise ConfigError(f"{where}: name = {cfg['name']!r} must match the file name {stem!r}")
    quick_table = cfg.pop("quick", {})
    full = dict(cfg) if quick and quick_table else None  # (a declaration's where may name values of the full grid)
    if quick:
        cfg.update(quick_table)
    if seed is not None:
        if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
            raise ConfigError(f"--seed must be a non-negative integer, got {seed!r}")
        cfg["seed"] = seed
    cfg.setdefault("seed", 0)
    schema.check_values(cfg, where)
    # a link to a TOML of another name stays the link: the file that was given, and whose name was checked above
    cfg = StudyConfig(cfg, where=where, folder=path.resolve().parent, quick=quick,
                      file=path.absolute().parent.resolve() / path.name)
    study.validate(cfg, where)
    validate_declarations(cfg, where, None if full is None else
                          StudyConfig({**full, "seed": cfg["seed"]}, where=where, folder=cfg.folder))
    return cfg


def plugin_notes(cfg: StudyConfig) -> list[str]:
    """One line per ``[[methods]]`` wildcard (``circle.*``) that takes methods of installed plugins: which methods of
    which distribution join the study (``python -m experiments.run`` prints them first). A shipped study's committed
    results were made without plugins: the line says how to reproduce them (docs/experiments.md)."""
    import methods
    from methods.plugins import distributions_of
    notes = []
    for entry in cfg.get("methods", []):
        mid = entry if isinstance(entry, str) else entry.get("id", "")
        if not isinstance(mid, str) or not mid.endswith(".*"):
            continue
        plugins = [s for s in methods.list_methods(mid[:-2]) if not s.builtin]
        if not plugins:
            continue
        by_dist: dict[str, list[str]] = {}
        for spec in plugins:
            dist = ", ".join(f"{d} {v}" for d, v in distributions_of([spec.module]).items()) or f"module {spec.module}"
            by_dist.setdefault(dist, []).append(spec.id)
        joined = "; ".join(f"{', '.join(ids)} of {dist}" for dist, ids in by_dist.items())
        shipped = cfg.folder.resolve() == CONFIG_DIR
        notes.append(f"{cfg['name']}: {len(plugins)} plugin method{'s join' if len(plugins) > 1 else ' joins'} "
                     f"{mid} ({joined})" + ("; the committed results were made without plugins: to reproduce them "
                                            "exactly, run in an environment without plugins (docs/experiments.md)"
                                            if shipped else ""))
    return list(dict.fromkeys(notes))


def check_rows(cfg: StudyConfig, n_rows: int, max_rows: int) -> None:
    if n_rows > max_rows:
        raise ConfigError(f"{cfg.where}: the grid has {n_rows:,} rows, more than the limit of {max_rows:,}; "
                          f"shrink the grid or pass --max-rows {n_rows}")
