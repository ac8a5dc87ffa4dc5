"""Unpickling of ``softrod.Simulation`` (its ``__reduce__`` names
:func:`restore`): a module-level function, so a pickle refers to it by name
in any process that has softrod."""

from __future__ import annotations

from softrod._softrod import Simulation


def restore(state: dict) -> Simulation:
    """The Simulation a pickled state dict describes (scene text, settings,
    initial state, held tensions, duration, warnings)."""
    return Simulation._from_state(state)
