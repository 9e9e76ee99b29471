"""Models named by reference, as the command line and case files name them.

A reference is ``package.module:Name`` (an importable module) or ``path/to/file.py:Name`` (a
Python file, imported under a private module name). ``Name`` is a model object, or a class or
function that returns one when called without arguments — a nonlinear model of one's own
(docs/models.md), an :class:`~rotorid.estimation.integrated.IntegratedModel` configured with
its channel map and initial conditions, or any identifiable model.
"""

from __future__ import annotations

import importlib
import importlib.util
import inspect
import re
import sys
from pathlib import Path

from rotorid.errors import StructureError
from rotorid.io import require_file

_REFERENCE = re.compile(r"^(?P<where>.+):(?P<name>[A-Za-z_]\w*)$")


def is_model_reference(text: str) -> bool:
    """Whether ``text`` has the form of a reference (not a model file such as ``m.toml``)."""
    match = _REFERENCE.match(str(text))
    if match is None:
        return False
    where = match["where"]
    return where.endswith(".py") or all(part.isidentifier() for part in where.split("."))


def load_model_reference(text: str):
    """The model ``text`` names (see the module docstring); classes and functions are called."""
    if not is_model_reference(text):
        raise StructureError(f"{text!r} is not a model reference; write package.module:Name "
                             "or path/to/file.py:Name")
    match = _REFERENCE.match(text)
    where, name = match["where"], match["name"]
    module = _module_from_file(Path(where)) if where.endswith(".py") else _module(where)
    if not hasattr(module, name):
        public = sorted(n for n in vars(module) if not n.startswith("_"))
        raise StructureError(f"{where} has no {name!r}; it defines {', '.join(public) or 'nothing'}")
    found = getattr(module, name)
    if not (inspect.isclass(found) or inspect.isfunction(found)):
        return found
    try:
        return found()
    except Exception as error:
        raise StructureError(f"{text}: calling {name}() failed ({type(error).__name__}: {error}); "
                             "it must build the model without arguments") from None


def _module(dotted: str):
    try:
        return importlib.import_module(dotted)
    except ImportError as error:
        raise StructureError(f"cannot import module {dotted!r} ({error}); check the name, "
                             "install its package or name a file: path/to/file.py:Name") from None
    except Exception as error:
        raise StructureError(f"importing {dotted!r} failed ({type(error).__name__}: "
                             f"{error})") from None


def _module_from_file(path: Path):
    require_file(path, "model file")
    module_name = f"_rotorid_model_{abs(hash(path.resolve()))}"
    spec = importlib.util.spec_from_file_location(module_name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[module_name] = module
    try:
        spec.loader.exec_module(module)
    except Exception as error:
        del sys.modules[module_name]
        raise StructureError(f"{path}: importing it failed ({type(error).__name__}: "
                             f"{error})") from None
    return module
