"""The exceptions ctxmodels raises about a value it was given.

Every error about an argument names it, and says what is wrong with it, as attributes as
well as in its message, so that a caller can react to *which* argument failed without
reading text::

    try:
        context.prob_detection_array(means)
    except ctxmodels.errors.ArgumentError as err:
        err.argument   # 'states'
        err.detail     # "row 3 is not finite (...)"
        str(err)       # 'states: row 3 is not finite (...)'

The Rust core's errors arrive as these classes (the binding maps each kind of core error to
one of them); the Python layer raises them for what it checks itself. They are
:class:`ValueError` (or, for :class:`ArgumentTypeError`, :class:`TypeError`) subclasses, so
``except ValueError`` keeps working. All pickle with their attributes.

======================================  ===================================================
class                                   raised when
======================================  ===================================================
:class:`ArgumentError`                  a value is wrong (out of range, unsorted, unknown
                                        name, ...)
:class:`ArgumentTypeError`              a value has the wrong type
:class:`ShapeError`                     arrays' shapes do not fit the call or each other
:class:`NonFiniteError`                 a row holds NaN or infinity where a number is
                                        needed
:class:`InvalidLandError`               a land mask's polygon, or one of its rings, is not
                                        valid land
:class:`NotPositiveDefiniteError`       a covariance the maths needs positive definite is
                                        not
:class:`InfeasibleAssignmentError`      an assignment problem has no assignment of finite
                                        cost
======================================  ===================================================

A buffer that cannot be allocated is Python's own :class:`MemoryError`, naming the argument
whose size asked for it in its message.
"""
from __future__ import annotations

__all__ = [
    "ArgumentError",
    "ArgumentTypeError",
    "InfeasibleAssignmentError",
    "InvalidLandError",
    "NonFiniteError",
    "NotPositiveDefiniteError",
    "ShapeError",
    "argument_error",
]


class _NamesArgument:
    """What the argument errors share: ``argument`` and ``detail`` as attributes and as the
    message ``"argument: detail"``; the constructor's arguments are the exception's
    ``args`` (so pickles rebuild it), the argument's name first."""

    argument: str
    detail: str

    def __init__(self, argument: str, detail: str, *more) -> None:
        super().__init__(argument, detail, *more)
        self.argument = argument
        self.detail = detail

    def __str__(self) -> str:
        return f"{self.argument}: {self.detail}"

    def renamed(self, argument: str):
        """The same error about ``argument``: what a function raises when a value its caller
        passed as ``argument`` failed under the name the function it called gave it."""
        err = type(self)(argument, *self.args[1:])
        err.__cause__, err.__traceback__ = self.__cause__, self.__traceback__
        return err


class ArgumentError(_NamesArgument, ValueError):
    """A value given to ctxmodels is wrong. :attr:`argument` names it as the function or
    component called spells it; :attr:`detail` says what is wrong."""


class ArgumentTypeError(_NamesArgument, TypeError):
    """A value given to ctxmodels has the wrong type (a :class:`TypeError`, with
    :attr:`argument` and :attr:`detail` as :class:`ArgumentError` has them)."""


class ShapeError(ArgumentError):
    """Array shapes do not fit together, or not the call (columns, rows, dimensions)."""


class NonFiniteError(ArgumentError):
    """An input row holds NaN or infinity where a finite number is needed: :attr:`row` is
    its index (the first such row)."""

    def __init__(self, argument: str, detail: str, row: int) -> None:
        super().__init__(argument, detail, row)
        self.row = row


class InvalidLandError(ArgumentError):
    """A land mask's polygon, or one of its rings, is not valid land (see
    :class:`~ctxmodels.LandMask`).

    :attr:`polygon` is the polygon's index. :attr:`ring` is ``None`` when the fault is
    the polygon's (its rings cross, a hole lies outside its shell, it overlaps another
    polygon: :attr:`detail` then names the rings), else the ring: 0 the shell, ``k + 1``
    hole ``k`` (GeoJSON's numbering of a polygon's rings), and :attr:`problem` is what is
    wrong with that ring without saying where."""

    def __init__(self, argument: str, detail: str, polygon: int, ring: int | None,
                 problem: str) -> None:
        super().__init__(argument, detail, polygon, ring, problem)
        self.polygon = polygon
        self.ring = ring
        self.problem = problem

    @property
    def ring_name(self) -> str | None:
        """``'shell'``, ``'hole k'``, or ``None`` when the fault is the polygon's."""
        if self.ring is None:
            return None
        return "shell" if self.ring == 0 else f"hole {self.ring - 1}"


class NotPositiveDefiniteError(ArgumentError):
    """A covariance the computation needs positive definite is not (its Cholesky
    factorisation failed)."""


class InfeasibleAssignmentError(ArgumentError):
    """An assignment problem has no complete assignment of finite cost."""


def argument_error(argument: str, detail: str, cause: BaseException) -> ArgumentError | ArgumentTypeError:
    """An error about ``argument`` saying ``detail``, raised because of ``cause`` (an error
    from inside the call: a pose source's, a nested argument's): a TypeError when ``cause``
    is one, else a ValueError, so callers catch what they would have caught from
    ``cause``."""
    kind = ArgumentTypeError if isinstance(cause, TypeError) else ArgumentError
    return kind(argument, detail)
