"""Gearboxes between a servo motor and a rotary load (``drive/data/gearboxes.toml``: ratio, the output torques
it carries, its inertia on the motor shaft), and the one rule that picks a motor and gearbox among the pairs
that carry a cycle: the smallest motor (least rated torque), then the least RMS torque. Used by the servo
sley against the loom's linkage (studies/linkage_servo.py) and by the sizing of a servo on a linkage's crank
(drive/sizing.py, a linkage through [drive] gearboxes)."""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from ..errors import ProblemError
from ..io.fields import Fields

KG_CM2 = 1e-4


@dataclass(frozen=True)
class GearboxEntry:
    """A gearbox of the catalogue: ``ratio`` motor turns per output turn, the output torques it carries [N m]
    (rated, the cycle's peak) and its inertia on the motor shaft [kg m^2]."""

    name: str
    ratio: float
    rated_output_torque: float
    peak_output_torque: float
    inertia: float
    model: str = ""
    source: str = ""


def gearbox_catalogue_file() -> Path:
    return Path(str(resources.files("strokeopt") / "drive" / "data" / "gearboxes.toml"))


def load_gearboxes(path: str | Path | None = None) -> list[GearboxEntry]:
    """The ``[[gearbox]]`` entries of ``path`` (default: the shipped drive/data/gearboxes.toml), validated."""
    path = Path(path) if path is not None else gearbox_catalogue_file()
    file = str(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise ProblemError(file, "", f"cannot be read: {exc}") from None
    top = Fields(data, file)
    out = []
    for row in top.tables("gearbox"):
        # ratios 1 (a direct drive) to 1000 (as [transmission] ratio); torques to 1e5 N m; inertias as a rotor's
        entry = GearboxEntry(row.string("name"), row.number("ratio", min=1.0, max=1000.0),
                             row.number("rated_output_torque_N_m", positive=True, max=1e5),
                             row.number("peak_output_torque_N_m", positive=True, max=1e5),
                             row.number("inertia_kg_cm2", min=0.0, max=1e6) * KG_CM2,
                             row.string("model", ""), row.string("source", ""))
        row.finish()
        if entry.peak_output_torque < entry.rated_output_torque:
            raise row.error("peak_output_torque_N_m", "is below the rated output torque")
        out.append(entry)
    top.finish()
    if len({g.name for g in out}) != len(out):
        raise ProblemError(file, "gearbox", "two gearboxes have the same name")
    return out


def choose_smallest(fits: list, rated, rms):
    """The pair to choose among ``fits`` (those that carry the cycle): the smallest motor (least ``rated(c)``
    torque), then the least ``rms(c)`` torque; None when nothing fits."""
    return min(fits, key=lambda c: (rated(c), rms(c))) if fits else None
