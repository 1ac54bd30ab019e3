"""What a report shows follows the machine: its output, its transmission, its motor, its handover, its scene.

:func:`machine_of` reads them from a problem (and the design's motor) once; the design report and the
comparison choose their sections, their columns and their words from it, so that a stepper's pull-out
curve is not called "rated curves", a screw and lever has no "pulley teeth", and an elastic chain's
report shows its link forces and its elastic-to-rigid ratios instead of an impact it does not have.
"""

from __future__ import annotations

from dataclasses import dataclass

#: The kinds of contact scene a report knows: the needle bar's (a follower that can lag the driven body, an
#: impact on a stop, a gap that must not close, a release) and an elastic chain on a transmission's members.
NEEDLE_BAR, ELASTIC_CHAIN, OTHER = "needle bar", "elastic chain", "other"


@dataclass(frozen=True)
class Machine:
    """What a problem has, for a report's words and sections.

    ``output``: what the stroke moves ("bar", "cam"); ``transmission``: "belt pulley" or "screw and lever"
    (or the transmission's name); ``pulley``: a belt pulley (teeth, pitch diameter); ``motor``: the design's
    motor name or None; ``stepper``: the motor is a stepper (pull-out curve, step rate) rather than a servo
    (peak and rated curves, RMS torque); ``handover``: a move ends at a handover; ``servo_model``: the problem
    models the servo loop and belt (a handover accuracy is predicted); ``scene``: the kind of contact scene
    (:data:`NEEDLE_BAR`, :data:`ELASTIC_CHAIN`, :data:`OTHER`) or None without a contact model.
    """

    output: str
    transmission: str
    pulley: bool
    motor: str | None
    stepper: bool
    handover: bool
    servo_model: bool
    scene: str | None

    @property
    def drive_words(self) -> str:
        """The drive in a few words: 'HY200-1713 (stepper) on a screw and lever', '055U2B30 (servo), 24-tooth
        pulley' (the teeth are the caller's: see :func:`drive_text`)."""
        kind = "stepper" if self.stepper else "servo"
        return f"{self.motor} ({kind})" if self.motor else "no motor"


def _output(problem) -> str:
    """What the stroke moves: on a staged model, the free body of the transmission's last member that nothing
    carries ('cam' on a screw and lever); else the bar of a belt-driven axis."""
    model = getattr(problem, "model", None)
    tr = getattr(model, "transmission", None) if model is not None else None
    if tr is not None:
        import casadi as ca

        last = [name for name, _, _ in tr.stages(ca.SX.sym("phi"))][-1]
        on_last = [b for b in model.bodies.values() if b.stage == last and not b.driven and b.rides_on is None]
        if on_last:
            return on_last[-1].name
        return last
    timing = getattr(problem, "timing", None)
    return "load" if getattr(timing, "rotary", False) else "bar"  # a rotary load: a sley, a turntable


def scene_kind(problem) -> str | None:
    """The kind of the problem's contact scenes (None without a contact model)."""
    model = getattr(problem, "model", None)
    if model is None or not getattr(problem, "scenes", None):
        return None
    if getattr(model, "transmission", None) is not None:
        return ELASTIC_CHAIN
    if getattr(model.events, "impact", None) or getattr(model.events, "follower", None):
        return NEEDLE_BAR
    return OTHER


def machine_of(problem, design=None) -> Machine:
    """The :class:`Machine` of ``problem`` with ``design``'s motor (its resolved drive when it has one)."""
    tr = problem.transmission
    motor = getattr(design, "motor", None) if design is not None else None
    spec = getattr(design, "motor_spec", None) if design is not None else None
    stepper = getattr(spec, "kind", "servo") == "stepper"
    return Machine(output=_output(problem), transmission=tr.label,
                   pulley=hasattr(tr, "radius"), motor=motor, stepper=stepper,
                   handover=problem.timing.handover_move is not None,
                   servo_model=getattr(problem, "servo", None) is not None and spec is not None,
                   scene=scene_kind(problem))


def drive_text(machine: Machine, summary: dict) -> str:
    """The motor and the transmission as one phrase: '055U2B30 (servo), 24-tooth pulley (PD 26.74 mm)',
    'HY200-1713 (stepper), screw and lever'."""
    if machine.pulley:
        teeth, pd = summary.get("pulley_teeth"), summary.get("pulley_pitch_diameter_mm")
        if teeth:
            pulley = f"{teeth}-tooth pulley" + (f" (PD {pd:.2f} mm)" if pd else "")
        elif pd:
            pulley = f"pulley of continuous diameter {pd:.2f} mm"
        else:
            pulley = "belt pulley"
        return f"{machine.drive_words}, {pulley}"
    return f"{machine.drive_words}, {machine.transmission}"
