"""The package around the compiled module ``dvrk_ident.dvrk_ident`` (the file maturin
writes for a pure Rust project, kept here so that the type stubs beside it,
``__init__.pyi`` and ``py.typed``, travel in the sdist too)."""

from .dvrk_ident import *  # noqa: F401,F403

__doc__ = dvrk_ident.__doc__  # noqa: F405
if hasattr(dvrk_ident, "__all__"):  # noqa: F405
    __all__ = dvrk_ident.__all__  # noqa: F405
