"""Circle family: one public module per method (every module of this folder whose name does not start with an
underscore registers what it decorates). Importing this package imports none of them, so that
``methods.circle.results`` (and :mod:`methods.results`) can be imported by the method modules themselves;
:func:`methods._registry.load_builtins` imports them (:func:`methods._families.import_method_modules`)."""
