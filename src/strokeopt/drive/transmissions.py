"""The transmissions a problem file may name: ``[transmission] type = "..."``, one line each.

A transmission is a position function of the motor angle with its transfer functions by AD
(:class:`~strokeopt.drive.transmission.Transmission`); its class reads its own ``[transmission]`` fields
(``read``), says what load it drives (``load_unit``) and names itself in reports (``label``). Adding one is
its own module, a line here and its tests: the problem reader, the design, the servo and contact code and
the reports take it from here.
"""

from __future__ import annotations

from .crank_slider import CrankSlider
from .transmission import BeltPulley, Gearbox, ScrewLever, Transmission

#: ``[transmission] type`` -> the class that reads it (the first is the default).
TRANSMISSIONS: dict[str, type[Transmission]] = {cls.name: cls for cls in (BeltPulley, ScrewLever, Gearbox, CrankSlider)}


def transmission_label(name: str | None) -> str | None:
    """A transmission's name (``"screw_lever"``) in words (``"screw and lever"``); an unknown name as it is,
    with spaces."""
    if name is None:
        return None
    cls = TRANSMISSIONS.get(name)
    return cls.label if cls is not None else name.replace("_", " ")
