"""Exception hierarchy: every error the package raises derives from :class:`IonicError`."""

from __future__ import annotations

__all__ = [
    "IonicError",
    "ParameterError",
    "GrammarError",
    "GeometryError",
    "BudgetError",
    "ReferenceCurveError",
    "OutputExistsError",
    "UsdAuthoringError",
]


class IonicError(Exception):
    """Root of all errors raised by ionic_usd.

    Every one pickles by its own ``__reduce__`` (a process pool or a Dask worker sends it
    back): without one, the exception pickling Dask installs (tblib) rebuilds an error through
    its built-in base's ``__new__``, which a :class:`BudgetError` (a ``MemoryError``) or an
    :class:`OutputExistsError` (a ``FileExistsError``) refuses.
    """

    def __reduce__(self):
        return type(self), self.args, self.__dict__ or None


class ParameterError(IonicError, ValueError):
    """A parameter is out of range, non-finite or inconsistent with another one.

    The message names the parameter, the value and the valid range.
    """

    def __init__(self, name: str, value: object, valid: str, *, context: str = "") -> None:
        self.name = name
        self.value = value
        self.valid = valid
        self.context = context
        where = f"{context}: " if context else ""
        super().__init__(f"{where}{name} = {value!r} is invalid; expected {valid}")

    def __reduce__(self):
        # picklable (a process pool or a Dask worker sends it back): rebuilt from its fields
        return _rebuild, (
            type(self),
            (self.name, self.value, self.valid),
            {"context": self.context},
        )


class GrammarError(IonicError, ValueError):
    """A grammar string could not be parsed.

    Carries the source, the character offset of the offending token, its length and the
    1-based module number, and renders the source with a caret under the token.
    """

    def __init__(
        self,
        message: str,
        source: str,
        offset: int,
        *,
        length: int = 1,
        module: int | None = None,
        grammar: str = "grammar",
    ) -> None:
        self.message = message
        self.source = source
        self.offset = max(0, min(offset, len(source)))
        self.length = max(1, length)
        self.module = module
        self.grammar = grammar
        super().__init__(self._render())

    def __reduce__(self):
        kwargs = {"length": self.length, "module": self.module, "grammar": self.grammar}
        return _rebuild, (type(self), (self.message, self.source, self.offset), kwargs)

    def with_grammar(self, grammar: str) -> GrammarError:
        """The same error (message, source, caret) under another grammar label, e.g. one that
        names the parameter the grammar came from."""
        return GrammarError(
            self.message,
            self.source,
            self.offset,
            length=self.length,
            module=self.module,
            grammar=grammar,
        )

    def get_context(self) -> str:
        """The source line with a caret (``^~~``) under the offending token."""
        line = self.source.replace("\n", " ")
        return f"  {line}\n  {' ' * self.offset}^{'~' * (self.length - 1)}"

    def _render(self) -> str:
        where = f" in module {self.module}" if self.module is not None else ""
        return (
            f"{self.grammar} error{where} at column {self.offset + 1}: {self.message}\n"
            f"{self.get_context()}"
        )


class GeometryError(IonicError, ValueError):
    """Geometry that cannot be built (e.g. a self-intersecting spiral band)."""


class BudgetError(IonicError, MemoryError):
    """A level of detail would exceed the configured triangle/memory budget."""


class ReferenceCurveError(IonicError, ValueError):
    """A reference curve file is unreadable, empty or malformed (names file and line)."""


class OutputExistsError(IonicError, FileExistsError):
    """An output exists and ``force`` was not given."""


class UsdAuthoringError(IonicError, RuntimeError):
    """A USD layer could not be composed or written (e.g. an unresolved reference)."""


def _rebuild(cls: type, args: tuple, kwargs: dict) -> BaseException:
    """An error rebuilt from its fields (:meth:`ParameterError.__reduce__`)."""
    return cls(*args, **kwargs)
