r"""The template of a law's compiled functions: its generated code with every float
literal lifted into a trailing argument.

:func:`law_template` turns a bound law (a sympy residual with its parameters' values)
into a :class:`LawTemplate`: the text of its kernel, term magnitude, branch selector,
branch kernels (in the stage form of ``radau5``) and branch guards as numba functions,
each float literal replaced by a name ``_c<k>`` (:func:`lift_constants`), and the
literals' values in order. A literal's text is ``repr`` of a float, so passing
``float(text)`` at run time computes what the literal computed, bit for bit; the text is
the same for every value of the law's numbers, except where a number changes the
generated source itself (0, a sign, an exponent written as a product or a square root, a
steep branch's inverse form; a factor of 1 stays in the code,
:func:`lumped.codegen.rewrite.constant_of`).
:mod:`lumped.codegen.jit` writes a scene's templates into one module per structure;
:mod:`lumped.solvers.bdf.fast_codegen` inlines them into a per-structure loop.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from .bounded_cache import remember
from .parametric import law_class
from .scene_key import law_key

__all__ = ["kernel_sources", "lift_constants", "lift_function", "slot_arguments",
           "LawTemplate", "law_template", "template_from_scratch"]


def kernel_sources(bound) -> tuple[str, str]:
    """``(kernel, magnitude)`` source of a bound law, unguarded (numba-ready)."""
    from lumped.codegen import compile_kernel

    _generated(bound)
    law = bound.law
    params = {law.symbols[p]: v for p, v in bound.params.items()}
    kernel = compile_kernel(law.residual, law.q, law.F, params, guard=False)
    return kernel.__source__, kernel.magnitude.__source__


def _generated(bound) -> None:
    """``ValueError`` unless ``bound``'s kernel is its sympy law's (a hand-written kernel
    has no generated code, whatever law and numbers it names)."""
    from lumped.laws import BoundLaw

    if not (isinstance(bound, BoundLaw) and type(bound).kernel is BoundLaw.kernel):
        raise ValueError(
            f"compiled methods need laws given as sympy residuals (ElementLaw.bind); got "
            f"{bound!r}, whose kernel is hand-written")


def _exact_powers(source: str) -> str:
    """Rewrite ``base**n`` (an integer literal ``n``) as ``math.pow(base, n.0)``.

    CPython evaluates ``x**3`` with the C library's ``pow``; numba expands an integer
    power into multiplications, which can differ in the last bit. ``math.pow`` is the C
    ``pow`` in both, so the compiled kernels give the Python kernels' numbers bit for bit.
    ``base`` is a name or a parenthesised group, with the call it belongs to if any.
    """
    out = source
    while True:
        m = re.search(r"\*\*(\d+)", out)
        if m is None:
            return out
        i = m.start()  # the operand ends just before i
        j = i
        if out[j - 1] == ")":
            depth = 0
            while True:
                j -= 1
                depth += {")": 1, "(": -1}.get(out[j], 0)
                if depth == 0:
                    break
        while j > 0 and (out[j - 1].isalnum() or out[j - 1] in "_."):
            j -= 1
        out = f"{out[:j]}math.pow({out[j:i]}, {m.group(1)}.0){out[m.end():]}"


#: A float literal of the generated code (``repr`` of a float: a point or an exponent),
#: not part of a name or an index.
_FLOAT_LITERAL = re.compile(r"(?<![\w.])(?:\d+\.\d*(?:[eE][+-]?\d+)?|\d+[eE][+-]?\d+)(?![\w.])")


#: A lifted name alone in parentheses that are not a call's or an index's.
_LONE_NAME = re.compile(r"(?<![\w\])\]])\((_c\d+)\)")


def lift_constants(body: str) -> tuple[str, list[float]]:
    """``body`` with its ``k``-th float literal replaced by the name ``_c<k>``, and the
    literals' values in order.

    A literal's text is ``repr`` of a float, so ``float(text)`` is the very double the
    literal stood for: the code given the values at run time computes what the code with
    the literals computed, bit for bit.
    """
    values: list[float] = []

    def slot(m: re.Match) -> str:
        values.append(float(m.group(0)))
        return f"_c{len(values) - 1}"

    lifted = _FLOAT_LITERAL.sub(slot, body)
    # sympy prints a Rational parameter (1/k of an integral k) as "(0.1)": the same
    # arithmetic as 0.1, but another text; a lone name in parentheses (not a call's) is
    # written bare, so integral and other values of a number give one template
    return _LONE_NAME.sub(r"\1", lifted), values


def lift_function(source: str, name: str) -> tuple[str, list[float]]:
    """``source`` (a generated kernel) as the numba function ``name``, its powers exact
    (:func:`_exact_powers`) and its body's float literals lifted
    (:func:`lift_constants`) into trailing arguments ``_c0, _c1, ...``: the *template* of
    the function (one text for every value of the law's parameters) and those values."""
    head, rest = _exact_powers(source).split("\n", 1)
    args = head[head.index("(") + 1:head.rindex(")")]
    body, values = lift_constants(rest)
    extra = "".join(f", _c{k}" for k in range(len(values)))
    inline = ', inline="always"' if name.startswith(("branch_", "guards_")) else ""
    return f"@njit(cache=True{inline})\ndef {name}({args}{extra}):\n{body}", values


def slot_arguments(array: str, start: int, count: int) -> str:
    """``", array[start], array[start + 1], ..."``: the lifted values of one call."""
    return "".join(f", {array}[{start + k}]" for k in range(count))


@dataclass(frozen=True)
class LawTemplate:
    """A bound law's generated functions with their float literals lifted
    (:func:`lift_function`).

    ``functions`` holds ``(stem, text, count)`` per function in the order ``law, mag,
    select, branch_0, guards_0, branch_1, guards_1, ...``; each text defines its function
    with ``@J@`` where the law's index in the module goes (``law_@J@``,
    ``branch_@J@_0``). ``values`` are the lifted literals in that order: the run-time
    constants of one element. Bound laws with equal ``functions`` share compiled code.
    """

    functions: tuple[tuple[str, str, int], ...]
    values: tuple[float, ...]
    branches: int
    #: the most guards of one branch (the compiled loops have room for :data:`GUARD_ROOM`)
    guards: int = 0

    def offset(self, stem: str) -> int:
        """Where function ``stem``'s values start in :attr:`values`."""
        at = 0
        for s, _, count in self.functions:
            if s == stem:
                return at
            at += count
        raise KeyError(stem)

    def count(self, stem: str) -> int:
        """How many values function ``stem`` takes."""
        return next(c for s, _, c in self.functions if s == stem)

    def call(self, stem: str, j: int, args: str, array: str, start: int) -> str:
        """The call of function ``stem`` of law ``j`` on ``args``, its values read from
        ``array`` where the element's values start at ``start``."""
        name = f"{stem}_{j}" if "_" not in stem else stem.replace("_", f"_{j}_", 1)
        return f"{name}({args}{slot_arguments(array, start + self.offset(stem), self.count(stem))})"

    def source(self, j: int) -> list[str]:
        """The definitions of law ``j``'s functions."""
        return [text.replace("@J@", str(j)) for _, text, _ in self.functions]


#: The most guards one branch of a law may have in the compiled loops, the room their
#: work arrays keep for a branch's guard values
#: (:func:`~lumped.solvers.eventdriven.loop_jit.loop_workspace`,
#: :func:`~lumped.solvers.modes.mode_guess_jit.probe_workspace`); a scene with a law that
#: has more runs in Python (:func:`~lumped.solvers.eventdriven.fast_parts.loop_parts`), as
#: numba checks no bounds.
GUARD_ROOM = 64

_TEMPLATES: dict[tuple, LawTemplate] = {}
#: :func:`law_template` per bound law's content (:func:`lumped.codegen.scene_key.law_key`).
_BY_LAW: dict[tuple, LawTemplate] = {}
#: Bound laws remembered with their templates (the oldest half forgotten past it).
_REMEMBERED = 4096


def law_template(bound) -> LawTemplate:
    """The :class:`LawTemplate` of a bound law given as a sympy residual (memoised by
    its generated sources; a law of a class :mod:`lumped.codegen.parametric` derives
    once gets the class's template with its own numbers). Kept per bound law's content
    (its law object and the bits of its numbers, :func:`~lumped.codegen.scene_key.
    law_key`), so that a law whose numbers have no class (an integral ``k``, ``tau = 1``)
    is derived from scratch once per process, not at every scene built with it."""
    key = law_key(bound)
    hit = _BY_LAW.get(key) if key is not None else None
    if hit is not None:
        return hit
    _generated(bound)  # (before its class: an object naming a law and numbers)
    rebound = law_class(bound)
    hit = rebound.template() if rebound is not None else template_from_scratch(bound)
    if key is not None:
        remember(_BY_LAW, key, hit, _REMEMBERED)
    return hit


def template_from_scratch(bound, lb=None) -> LawTemplate:
    """:func:`law_template` derived from the bound law's numbers (``lb``: its
    :class:`~lumped.codegen.branches.LawBranches` when already made)."""
    ksrc, msrc = kernel_sources(bound)
    selector, branches = _branches(bound, lb)
    key = (ksrc, msrc, selector, tuple(branches))
    hit = _TEMPLATES.get(key)
    if hit is not None:
        return hit
    parts = [("law", "law_@J@", ksrc), ("mag", "mag_@J@", msrc),
             ("select", "select_@J@", selector)]
    for i, (bsrc, codes) in enumerate(branches):
        lines = ["def guards(q, F, out):"]
        lines += [f"    out[{m}] = {code}" for m, code in enumerate(codes)]
        lines += [f"    return {len(codes)}", ""]
        parts += [(f"branch_{i}", f"branch_@J@_{i}", bsrc),
                  (f"guards_{i}", f"guards_@J@_{i}", "\n".join(lines))]
    functions, values = [], []
    for stem, name, src in parts:
        text, vals = lift_function(src, name)
        functions.append((stem, text, len(vals)))
        values += vals
    hit = _TEMPLATES[key] = LawTemplate(tuple(functions), tuple(values), len(branches),
                                        max((len(codes) for _, codes in branches), default=0))
    return hit


def _branches(bound, lb=None):
    """``(selector source, [(kernel source, guard codes), ...])`` of a law's smooth
    branches (:func:`lumped.codegen.branches.law_branches`; the kernels in the form the
    stage solve of ``radau5`` takes, ``stage_source_for``)."""
    from lumped.codegen.branches import law_branches
    from lumped.codegen.rebinding import codes_of, source_of

    lb = law_branches(bound) if lb is None else lb
    return source_of(lb.branch), [(lb.stage_source_for(i), codes_of(lb.stage_guards_for(i)))
                                  for i in range(lb.count)]
