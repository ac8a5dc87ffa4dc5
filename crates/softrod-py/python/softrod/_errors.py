"""The exceptions softrod raises.

Every error of the package derives from :class:`SoftrodError`. Bad input is
also a :class:`ValueError` and a failed computation a :class:`RuntimeError`,
so ``except ValueError`` keeps working for code that does not know softrod.
"""

from __future__ import annotations


class SoftrodError(Exception):
    """Base class of every softrod error."""


class InputError(SoftrodError, ValueError):
    """Bad input: a wrong shape (the message names the argument and both
    shapes), an invalid setting, rod, material, load or cable."""


class SceneError(InputError):
    """An invalid scene file or text; the message names the file, line,
    column and key path (e.g. ``rod[0].material.young``)."""


class SimulationError(SoftrodError, RuntimeError):
    """A computation failed on valid input (integration, statics, a singular
    matrix). ``time`` is the simulation time of the failure [s] when known,
    else None."""

    time: float | None = None


class NotSupportedError(SoftrodError, NotImplementedError):
    """The method does not cover a part of this model yet: the Coriolis
    matrix of a model with joints or bodies, inverse dynamics, derivatives
    and linearization of a model with loop closures. The message names
    the method."""


class InternalError(SoftrodError, RuntimeError):
    """A bug inside softrod (a Rust panic, caught at the boundary instead of
    aborting the interpreter). Please report it with the message."""


__all__ = [
    "InputError",
    "InternalError",
    "NotSupportedError",
    "SceneError",
    "SimulationError",
    "SoftrodError",
]
