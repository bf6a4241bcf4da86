r"""Keys of a scene's content, for what is kept per scene *content* rather than per scene
object.

A user's first run builds a new :class:`~lumped.scene.Scene` object, and a study that
edits a number builds another: what a run derives from a scene (its plan, its start at
rest, its generated module's text) kept per scene object is made again for each of
them. :func:`scene_key` is a key of everything a run reads from a plain scene, so that
two scene objects with equal keys give the same numbers from one kept derivation:

* per node, in order: its type (:class:`~lumped.scene.Mass` or
  :class:`~lumped.scene.Junction`), name, and the bits of ``m``, ``x0``, ``v0``;
* per element, in order: its name, its ends' names, whether it has an ``F0`` (and its
  bits), its law: a :class:`~lumped.laws.BoundLaw`'s :class:`~lumped.laws.ElementLaw`
  *object* (the same object, not an equal one) and the bits of its parameters in the
  law's order; any other law object itself (by identity);
* per node's forcing: none, a constant (the bits of its value), a
  :class:`~lumped.scene.forcing.SineBurst` of floats (the bits of its numbers), any
  other forcing object itself (by identity).

"The bits" are the IEEE doubles packed by :mod:`struct` (``-0.0`` differs from ``0.0``);
a number that is not a ``float`` gives no key. An object compared by identity enters
the key as its ``id``, and the key comes with those objects (``held``): whoever keeps the
key keeps them, so that no other object takes their ``id`` while it lives. A scene with
a ground motion, supports, a support frame or clock, or of a subclass of ``Scene`` has
no key (``None``): it is kept per object, as before.
"""

from __future__ import annotations

import struct

from ..laws import BoundLaw
from ..scene import Element, Junction, Mass, Scene
from ..scene.forcing import SineBurst
from ..scene.forcing_spec import ConstantForce

__all__ = ["law_key", "scene_key"]


def scene_key(scene: object) -> tuple[tuple, tuple] | None:
    """``(key, held)``: the key of ``scene``'s content (see the module notes) and the
    objects it names by ``id``, which the keeper of the key must hold; or ``None`` when
    the scene has no key (it is then kept per object).

    The key is one flat tuple of fixed-width records after the counts of nodes and
    elements (a node: 2 fields; an element: 6; a forcing: 2), then the numbers' bits."""
    if (type(scene) is not Scene or scene.ground_motion is not None or scene.supports
            or scene.support_ends or scene.support_clock is not None
            or getattr(scene, "support_frame", None) is not None):
        return None
    nums: list[float] = []
    parts: list[object] = [len(scene.nodes), len(scene.elements)]
    held: list[object] = []
    for nd in scene.nodes:
        kind = type(nd)
        if kind is Mass:
            parts += ("m", nd.name)
            nums += (nd.m, nd.x0, nd.v0)
        elif kind is Junction:
            parts += ("j", nd.name)
            nums.append(nd.x0)
        else:
            return None
    for el in scene.elements:
        if type(el) is not Element:
            return None
        law = el.law
        if type(law) is BoundLaw:
            held.append(law.law)
            parts += (el.name, el.a, el.b, el.F0 is None, True, id(law.law))
            nums += law._params.values()
        else:
            held.append(law)
            parts += (el.name, el.a, el.b, el.F0 is None, False, id(law))
        if el.F0 is not None:
            nums.append(el.F0)
    for fn in scene.forcing:
        kind = type(fn)
        if fn is None:
            parts += (0, None)
        elif kind is ConstantForce:
            parts += (1, None)
            nums.append(fn.value)
        elif kind is SineBurst and type(fn.amplitude) is float and type(fn.omega) is float \
                and type(fn.t_off) is float:
            parts += (2, None)
            nums += (fn.amplitude, fn.omega, fn.t_off)
        else:
            held.append(fn)
            parts += (3, id(fn))
    for v in nums:
        if type(v) is not float:
            return None
    parts.append(struct.pack(f"{len(nums)}d", *nums))
    return tuple(parts), tuple(held)


def law_key(bound: object) -> tuple | None:
    """The key of a bound law's content, for a :class:`~lumped.laws.BoundLaw` of floats:
    ``(ElementLaw, bits of its parameters in the law's order)`` (the law compared by
    identity first, as a dictionary does, then by its own equality); ``None`` for
    anything else."""
    if type(bound) is not BoundLaw:
        return None
    values = tuple(bound._params.values())
    for v in values:
        if type(v) is not float:
            return None
    return bound.law, struct.pack(f"{len(values)}d", *values)
