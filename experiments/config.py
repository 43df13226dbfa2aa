"""Study configs: one TOML file per study in ``experiments/configs/`` (or any path), validated on load."""
from __future__ import annotations

import importlib
import tomllib
from pathlib import Path

from experiments.engine import ConfigError

CONFIG_DIR = Path(__file__).resolve().parent / "configs"
REQUIRED = ("name", "title", "kind")


def available() -> dict[str, Path]:
    return {p.stem: p for p in sorted(CONFIG_DIR.glob("*.toml"))}


def load(name: str, *, quick: bool = False, seed: int | None = None) -> dict:
    """The config of study ``name`` (or of a .toml path), with its ``[quick]`` table applied when
    ``quick`` and ``seed`` overriding its seed. Errors name the file, the key and the problem."""
    path = Path(name)
    if path.suffix == ".toml" and path.exists():
        stem = path.stem
    else:
        configs = available()
        if name not in configs:
            raise ConfigError(f"unknown study {name!r}; 'python -m experiments.run --list' shows them "
                              f"({', '.join(configs) or 'none'})")
        path, stem = configs[name], name
    where = path.name
    try:
        cfg = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{where}: not valid TOML ({exc})") from None
    for key in REQUIRED:
        if key not in cfg:
            raise ConfigError(f"{where}: missing required key {key!r}")
    if cfg["name"] != stem:
        raise ConfigError(f"{where}: name = {cfg['name']!r} must match the file name {stem!r}")
    quick_table = cfg.pop("quick", {})
    if not isinstance(quick_table, dict):
        raise ConfigError(f"{where}: [quick] must be a table of overrides")
    if quick:
        cfg.update(quick_table)
    if seed is not None:
        cfg["seed"] = seed
    cfg.setdefault("seed", 0)
    if not isinstance(cfg["seed"], int):
        raise ConfigError(f"{where}: seed must be an integer, got {cfg['seed']!r}")
    try:
        study = importlib.import_module(f"experiments.studies.{cfg['kind']}")
    except ModuleNotFoundError:
        raise ConfigError(f"{where}: unknown kind {cfg['kind']!r} (a module in experiments/studies/)") from None
    cfg["_where"] = where
    cfg["_dir"] = str(path.resolve().parent)
    cfg["_quick"] = quick
    from experiments.study import validate as validate_declarations
    validate_declarations(cfg, where)
    if hasattr(study, "validate"):
        study.validate(cfg, where)
    return cfg
