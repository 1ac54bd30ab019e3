"""The resolved drive: the motor, transmission, belt, limits and load of a design, made once and handed on.

A problem file names its motor, pulley and belt (``[drive] motor``, ``[transmission] pulley_teeth``,
``[drive] belt``); a design chooses them (a catalogue search, a continuous radius). :func:`resolve_drive`
looks the names up in the catalogue once and returns a :class:`ResolvedDrive`; a
:class:`~strokeopt.design.result.Design` holds it, and the servo simulation, the torque figures, the
comparison with the classic laws and the report take their parts from it instead of looking a motor or a
pulley up by name again.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..errors import ProblemError
from .catalogue import Catalogue, Pulley
from .transmission import BeltPulley, Transmission, pitch_diameter


def catalogue_pulley(catalogue: Catalogue, profile: str, teeth: int) -> Pulley:
    """The catalogue's pulley of ``teeth`` grooves, or one made from the profile's pitch and fitted inertia
    model when the catalogue lists none (``inertia_source = "model"``)."""
    found = catalogue.pulleys_of(profile, teeth, teeth)
    if found:
        return found[0]
    pd = pitch_diameter(profile, teeth)
    return Pulley(f"{profile}-{teeth}", profile, teeth, pd, float(catalogue.pulley_inertia(profile, pd)), "model")


@dataclass(frozen=True)
class ResolvedDrive:
    """A drive whose parts are catalogue entries, not names.

    ``actuator``: the servo motor or stepper (None when the problem names none); ``transmission``: the
    problem's own (a screw and lever) or the belt pulley of the chosen teeth or continuous pitch diameter,
    with the pulley's inertia when ``[design] include_pulley_inertia``; ``pulley``: the catalogue pulley
    (teeth, radius, inertia; None for a continuous radius or no pulley); ``pitch_diameter``: the continuous
    one; ``belt``: the belt checks' spec (``[drive] belt``) or None; ``spec``: the ``[drive]`` section
    (load, limits, profile)."""

    actuator: Any
    transmission: Transmission
    pulley: Pulley | None
    pitch_diameter: float | None
    belt: Any
    spec: Any
    catalogue: Catalogue

    @property
    def motor(self) -> str | None:
        return None if self.actuator is None else self.actuator.name

    @property
    def pulley_teeth(self) -> int | None:
        return None if self.pulley is None else self.pulley.teeth

    @property
    def radius(self) -> float | None:
        """The pulley's pitch radius [m] (catalogue or continuous); None without a belt pulley."""
        if self.pulley is not None:
            return self.pulley.radius
        return None if self.pitch_diameter is None else self.pitch_diameter / 2

    @property
    def pulley_inertia(self) -> float:
        """The pulley's own inertia [kg m^2] (catalogue, or the profile's model for a continuous radius)."""
        if self.pulley is not None:
            return self.pulley.inertia
        if self.pitch_diameter is None:
            return 0.0
        return float(self.catalogue.pulley_inertia(self.spec.profile, self.pitch_diameter))

    @property
    def load(self):
        return self.spec.load

    @property
    def limits(self):
        return self.spec.limits

    def provenance(self) -> dict:
        """The motor and pulley as every report names them (``drive`` of ``solve --json``), without ``from``."""
        out = {"motor": self.motor, "pulley_teeth": self.pulley_teeth}
        if not isinstance(self.transmission, BeltPulley):
            out["transmission"] = self.transmission.name
        return out


def resolve_drive(problem, *, motor=None, pulley_teeth: int | None = None, pitch_diameter: float | None = None,
                  include_pulley_inertia: bool = True) -> ResolvedDrive | None:
    """The drive of ``problem`` with ``motor`` (a catalogue entry or a name; default ``[drive] motor``) and
    the pulley of ``pulley_teeth`` or of the continuous ``pitch_diameter`` [m] (default
    ``[transmission] pulley_teeth``); None when the problem has no ``[drive]`` section. A name the catalogue
    does not have is refused naming the field."""
    spec = getattr(problem, "drive", None)
    if spec is None:
        return None
    file = str(problem.file)
    catalogue = spec.catalogue()
    name = motor if isinstance(motor, str) else None if motor is not None else spec.motor
    actuator = motor if motor is not None and not isinstance(motor, str) else \
        None if name is None else catalogue.actuator(name, (file, "drive.motor"))
    pulley, pd = None, None
    if not isinstance(problem.transmission, BeltPulley):  # a screw and lever: the problem's own
        transmission = problem.transmission
    elif pitch_diameter is not None and pulley_teeth is None:
        pd = float(pitch_diameter)
        inertia = catalogue.pulley_inertia(spec.profile, pd) if include_pulley_inertia else 0.0
        transmission = BeltPulley(pd, inertia=float(inertia))
    else:
        teeth = pulley_teeth if pulley_teeth is not None else problem.pulley_teeth
        if teeth is None:
            raise ProblemError(file, "transmission.pulley_teeth", "the drive needs the pulley's tooth count")
        pulley = catalogue_pulley(catalogue, spec.profile, int(teeth))
        transmission = BeltPulley(pulley.pitch_diameter, inertia=pulley.inertia if include_pulley_inertia else 0.0,
                                  teeth=pulley.teeth, profile=pulley.profile)
    return ResolvedDrive(actuator, transmission, pulley, pd, spec.belt_spec(catalogue), spec, catalogue)
