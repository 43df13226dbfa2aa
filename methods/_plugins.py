"""The plugin loader moved to the public :mod:`methods.plugins`; this name stays for old imports."""
from methods.plugins import *  # noqa: F401,F403
from methods.plugins import _loaded_groups, _one_line  # noqa: F401
