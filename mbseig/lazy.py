"""Names of a package imported on first use (PEP 562), so that importing the package costs
nothing beyond itself: ``__getattr__, __dir__ = lazy_names(__name__, globals(), table)``."""

import importlib

__all__ = ["lazy_names"]


def lazy_names(package: str, namespace: dict, table: dict):
    """(``__getattr__``, ``__dir__``) of ``package`` whose public names are ``table``: name →
    the submodule (relative) that defines it; once imported, a name is an ordinary attribute."""

    def __getattr__(name):
        module = table.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f".{module}", package), name)
        namespace[name] = value
        return value

    def __dir__():
        return sorted(set(namespace) | set(table))

    return __getattr__, __dir__
