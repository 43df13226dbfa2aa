"""Circle family: importing this package registers its methods, one public module each (every module of this
folder whose name does not start with an underscore is imported and registers what it decorates)."""
from methods._families import import_method_modules

METHOD_MODULES = import_method_modules(__name__, __path__)
