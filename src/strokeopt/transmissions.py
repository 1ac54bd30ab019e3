"""The transmissions a problem file may name: ``[transmission] type = "..."``, one line each.

A transmission is a position function of the motor angle with its transfer functions by AD
(:class:`~strokeopt.drive.transmission.Transmission`); its class reads its own ``[transmission]`` fields
(``read``), says what load it drives (``load_unit``; None: its fields decide, as a linkage's output) and names
itself in reports (``label``). Adding one is its own module, a line here and its tests: the problem reader, the
design, the servo and contact code and the reports take it from here. The registry sits above the packages it
lists (drive's transmissions, the linkage's), so none of them imports another for it.
"""

from __future__ import annotations

from .drive.crank_slider import CrankSlider
from .drive.screw_lever import ScrewLever
from .drive.transmission import BeltPulley, Gearbox, Transmission
from .linkage.transmission import LinkageTransmission

#: ``[transmission] type`` -> the class that reads it (the first is the default).
TRANSMISSIONS: dict[str, type[Transmission]] = {cls.name: cls for cls in (BeltPulley, ScrewLever, Gearbox, CrankSlider,
                                                                          LinkageTransmission)}


def transmission_label(name: str | None) -> str | None:
    """A transmission's name (``"screw_lever"``) in words (``"screw and lever"``); an unknown name as it is,
    with spaces."""
    if name is None:
        return None
    cls = TRANSMISSIONS.get(name)
    return cls.label if cls is not None else name.replace("_", " ")
