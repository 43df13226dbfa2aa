"""fitbench experiments: study configs (TOML), the runner (``python -m experiments.run``), timing,
provenance."""
