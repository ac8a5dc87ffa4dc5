"""Builders of the scene tables a Python program needs beyond rods: bodies,
joints (prescribed or not), loop closures, obstacles and contact settings.

Each builder returns the plain dict of the scene file's table with the same
keys (docs/scene-format.md), leaving out what is not given, so that the
scene's own default applies: the scene loader is the one place that knows
the defaults and checks the values (errors name the key path, e.g.
``body[0].mass``). The dicts go to ``softrod.Simulation(rods, ...,
bodies=, closures=, obstacles=, contact=)``, to ``softrod.Rod(...,
joint=)`` or into a scene dict for ``softrod.Simulation.from_dict``.

>>> import softrod
>>> softrod.Joint("revolute", axis=[0, 1, 0])
{'type': 'revolute', 'axis': [0, 1, 0]}
>>> softrod.Obstacle("table", "plane", normal=[0, 0, 1], friction=0.5)
{'name': 'table', 'shape': 'plane', 'normal': [0, 0, 1], 'friction': 0.5}
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

__all__ = [
    "Base",
    "Body",
    "Closure",
    "ContactSettings",
    "Frame",
    "Joint",
    "Obstacle",
    "Prescribed",
]


def _table(**keys: Any) -> dict[str, Any]:
    """The keys that were given (None: the scene's default)."""
    return {k: v for k, v in keys.items() if v is not None}


def Base(position: Sequence[float] | None = None,
         rotation: Sequence[Sequence[float]] | None = None) -> dict[str, Any]:
    """A ``base`` pose: ``position`` [m] (default the origin) and
    ``rotation`` (3x3, orthonormal, det +1; default identity), relative to
    the attachment frame."""
    return _table(position=position, rotation=rotation)


def Prescribed(times: Sequence[float], values: Any) -> dict[str, Any]:
    """A joint's ``prescribed`` motion: the joint follows the C2 curve
    through ``values`` at ``times`` [s] (one column per joint DoF; a list of
    lists for more than one). A prescribed joint is no DoF; its drive's
    force is an output (``Simulation.prescribed_forces``)."""
    return {"times": times, "values": values}


def Joint(type: str = "fixed", *, axis: Sequence[float] | None = None,
          axes: Sequence[Sequence[float]] | None = None,
          stiffness: Any = None, damping: Any = None, rest: Any = None,
          prescribed: Mapping[str, Any] | None = None,
          actuator: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """A ``joint`` table: ``type`` "fixed" (default), "revolute" or
    "prismatic" (``axis`` in the element's frame), "universal" (``axes``,
    two), "spherical" (rotation vector) or "free" (rotation vector,
    translation: a floating base); per DoF, optional ``stiffness``,
    ``damping`` (SI) and ``rest`` (the value at zero force);
    ``prescribed``: see ``Prescribed``; ``actuator``: ``{"force": ...,
    "max_force": ...}``, a generalized force per DoF [N or N m] (a number,
    one per DoF, or ``{"times", "values"}``) and its bound for
    ``solve_actuation`` (docs/theory-control.md IS14)."""
    return _table(type=type, axis=axis, axes=axes, stiffness=stiffness,
                  damping=damping, rest=rest, prescribed=prescribed,
                  actuator=actuator)


def Body(name: str, parent: str, *, mass: float, inertia: Any,
         center_of_mass: Sequence[float] | None = None, at: float | None = None,
         base: Mapping[str, Any] | None = None,
         joint: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """A ``[[body]]`` table: a rigid body ``name`` hanging from ``parent``
    ("world", a rod or a body) at ``at`` [m] on a parent rod (default its
    tip), through ``joint`` (default fixed), its frame at ``base`` relative
    to the attachment; ``mass`` [kg], ``inertia`` [kg m^2] about the centre
    of mass in body axes (principal [Ixx, Iyy, Izz] or a 3x3 matrix),
    ``center_of_mass`` [m] in the body frame (default the origin)."""
    return _table(name=name, parent=parent, at=at, base=base, joint=joint,
                  mass=mass, inertia=inertia, center_of_mass=center_of_mass)


def Frame(element: str, *, at: float | None = None,
          base: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """A closure's frame: ``element`` a rod (at arc length ``at`` [m],
    default its tip), a body, or "world", then the offset pose ``base``."""
    return _table(element=element, at=at, base=base)


def Closure(type: str, a: Mapping[str, Any], b: Mapping[str, Any], *,
            name: str | None = None,
            axis: Sequence[float] | None = None) -> dict[str, Any]:
    """A ``[[closure]]`` table holding frames ``a`` and ``b`` (see
    ``Frame``) together: ``type`` "weld" (all six relative motions), "ball"
    (positions only) or "slider" (a's origin on the line through b along
    ``axis``, in b's frame)."""
    return _table(name=name, type=type, a=a, b=b, axis=axis)


def Obstacle(name: str, shape: str, *, position: Sequence[float] | None = None,
             normal: Sequence[float] | None = None,
             axis: Sequence[float] | None = None, radius: float | None = None,
             length: float | None = None,
             rotation: Sequence[Sequence[float]] | None = None,
             half_extents: Sequence[float] | None = None,
             parent: str | None = None, friction: float | None = None,
             restitution: float | None = None) -> dict[str, Any]:
    """An ``[[obstacle]]`` table: a rigid ``shape`` rods cannot enter, in
    its ``parent``'s frame ("world" default: fixed; a body's name: carried
    by it, and the contact forces act on it). "plane" (``position``,
    ``normal``: rods stay on its side), "sphere" (``radius``), "cylinder"
    (``axis``, ``radius``; infinite), "capsule" (``axis``, ``length``,
    ``radius``; centred at ``position``), "box" (``rotation``,
    ``half_extents``). ``friction``: Coulomb coefficient (default 0),
    ``restitution`` in [0, 1] (default 0)."""
    return _table(name=name, shape=shape, position=position, normal=normal,
                  axis=axis, radius=radius, length=length, rotation=rotation,
                  half_extents=half_extents, parent=parent, friction=friction,
                  restitution=restitution)


def ContactSettings(*, rods: bool | None = None, friction: float | None = None,
                    restitution: float | None = None,
                    **keys: Any) -> dict[str, Any]:
    """The ``[contact]`` table: ``rods`` (different rods touch each other),
    ``self`` (a rod touches itself; a Python keyword, so give it as
    ``**{"self": True}`` or ``self_contact=True``), ``friction`` and
    ``restitution`` between rods (defaults false, false, 0, 0)."""
    extra = dict(keys)
    if "self_contact" in extra:
        extra["self"] = extra.pop("self_contact")
    return _table(rods=rods, friction=friction, restitution=restitution, **extra)
