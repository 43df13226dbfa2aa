"""Study kind ``grid``: the generic benchmark (data sets x repetitions x methods) with no analysis
beyond the summary tables. Use it for your own configs: ``python -m experiments.run my_study.toml``."""
