"""Study configs: one TOML file per study in ``experiments/configs/``, validated on load."""
from __future__ import annotations

import tomllib
from pathlib import Path

import datasets
import methods
from methods import InvalidInputError

CONFIG_DIR = Path(__file__).resolve().parent / "configs"


class ConfigError(InvalidInputError):
    """A study config that cannot run; the message names the file and the entry."""


def available() -> dict[str, Path]:
    return {p.stem: p for p in sorted(CONFIG_DIR.glob("*.toml"))}


def expand_methods(entries, where: str) -> list[str]:
    """Method ids from a config list; 'family.*' expands to every registered method of the family."""
    ids = []
    for entry in entries:
        if not isinstance(entry, str):
            raise ConfigError(f"{where}: method entries must be ids, got {entry!r}")
        if entry.endswith(".*"):
            found = [s.id for s in methods.list_methods(entry[:-2])]
            if not found:
                raise ConfigError(f"{where}: no registered methods in family {entry[:-2]!r}")
            ids += found
        else:
            try:
                ids.append(methods.get(entry).id)
            except methods.UnknownMethodError as exc:
                raise ConfigError(f"{where}: {exc}") from None
    return list(dict.fromkeys(ids))


def parse_dataset(entry: str, where: str) -> tuple[str, dict]:
    name, _, variant = entry.partition(":")
    if name not in datasets.list():
        raise ConfigError(f"{where}: unknown data set {name!r}; known: {', '.join(datasets.list())}")
    options = {}
    if variant:
        if variant != "drop_repeated_closing_point":
            raise ConfigError(f"{where}: unknown data set variant {variant!r} (known: drop_repeated_closing_point)")
        options[variant] = True
    return name, options


def load(name: str) -> dict:
    configs = available()
    if name not in configs:
        raise ConfigError(f"unknown study {name!r}; 'python -m experiments.run --list' shows them "
                          f"({', '.join(configs) or 'none'})")
    path = configs[name]
    try:
        cfg = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path.name}: not valid TOML ({exc})") from None
    where = path.name
    for key in ("name", "title", "kind", "datasets", "methods"):
        if key not in cfg:
            raise ConfigError(f"{where}: missing required key {key!r}")
    if cfg["name"] != name:
        raise ConfigError(f"{where}: name = {cfg['name']!r} must match the file name {name!r}")
    cfg["_datasets"] = [parse_dataset(e, where) for e in cfg["datasets"]]
    cfg["_methods"] = expand_methods(cfg["methods"], where)
    for i, var in enumerate(cfg.get("variants", [])):
        mid = expand_methods([var.get("method", "")], f"{where} variants[{i}]")[0]
        spec = methods.get(mid)
        bad = set(var.get("params", {})) - set(spec.defaults)
        if bad:
            raise ConfigError(f"{where} variants[{i}]: {mid} has no parameter(s) {', '.join(sorted(bad))}")
    return cfg
