"""Lazy public names for a package's ``__init__`` (PEP 562), in the manner of
scientific-python's ``lazy_loader.attach``: ``import axialdeform`` and every
CLI start pay only for the modules a program touches."""

from __future__ import annotations

import sys
import warnings
from importlib import import_module
from importlib.util import find_spec

__all__ = ["attach"]


def attach(package: str, names: dict[str, str], deprecated: dict[str, str] | None = None):
    """``(__getattr__, __dir__, __all__)`` for ``package``.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    names : dict of str to str
        Public name -> the submodule (relative to ``package``) that is its home.
    deprecated : dict of str to str, optional
        Old name -> its new home as a dotted path (``"axialdeform.core.ParamError"``);
        reading it warns (DeprecationWarning) and returns the object there.
    """
    deprecated = deprecated or {}

    def __getattr__(name: str):
        module = sys.modules[package]
        if name in names:
            value = getattr(import_module(f".{names[name]}", package), name)
        elif name in deprecated:
            home, _, attr = deprecated[name].rpartition(".")
            warnings.warn(f"{package}.{name} is deprecated and goes in the next release: use {deprecated[name]}",
                          DeprecationWarning, stacklevel=2)
            return getattr(import_module(home), attr)  # not cached: every use warns
        else:

            if name.startswith("_") or find_spec(f"{package}.{name}") is None:
                raise AttributeError(f"module {package!r} has no attribute {name!r}")
            value = import_module(f".{name}", package)  # a submodule
        setattr(module, name, value)
        return value

    def __dir__():
        return sorted(set(vars(sys.modules[package])) | set(names))

    return __getattr__, __dir__, sorted(names)
