"""Modes and events: which branch of its law every element is held on, and when that changes.

:mod:`.guards` and :mod:`.crossing_root` (guards along a step and their first crossing),
:mod:`.choice` (the next mode at an event, by a vanishing implicit step),
:mod:`.mode_guess` (a guessed mode confirmed by the full laws; compiled:
:mod:`.mode_guess_jit`), :mod:`.lock_events` (impacts, locks and their cones at an
event), :mod:`.split_kink` (kinks of the split among locks in a step) and :mod:`.stuck`
(stuck intervals taken in one piece; their static balance :mod:`.static_balance`;
compiled: :mod:`.stuck_jit`), :mod:`.junctions_at` (the junctions' velocities at the
start's ``t`` itself, not at the end of its probe).
"""
