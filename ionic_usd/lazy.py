"""Names of a package imported on first use (PEP 562), so importing the package stays light.

>>> getattr_, dir_ = lazy_attributes("pkg", {"sqrt": "math"}, {})
>>> getattr_("sqrt")(4.0)
2.0
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping, MutableMapping
from typing import Any

__all__ = ["lazy_attributes"]


def lazy_attributes(
    package: str, names: Mapping[str, str], namespace: MutableMapping[str, Any]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """A module ``__getattr__`` and ``__dir__`` for ``package``.

    Parameters
    ----------
    package : the package's ``__name__`` (for the AttributeError message)
    names : public name → the module that defines it
    namespace : the package's ``globals()``: a name, once imported, is stored there, so later
        look-ups do not reach ``__getattr__``

    Use in a package's ``__init__.py``::

        __getattr__, __dir__ = lazy_attributes(__name__, _NAMES, globals())
    """

    def getattr_(name: str) -> Any:
        module = names.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module), name)
        namespace[name] = value
        return value

    def dir_() -> list[str]:
        return sorted({*namespace.get("__all__", ()), *names})

    return getattr_, dir_
