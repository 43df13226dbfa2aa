"""Study kind ``grid``: the generic benchmark (data sets x repetitions x methods) with no analysis
beyond the declared (or default) tables and figures. A TOML without ``kind`` runs it too:
``python -m experiments.run my_study.toml``."""
from experiments.study import Study


class GridStudy(Study):
    """The generic benchmark: every default of :class:`experiments.study.Study`."""
