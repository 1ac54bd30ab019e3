"""The servo axis: how far the bar is from its commanded position, and what accuracy costs.

Modules in data-flow order:

* ``settings``  -- the ``[servo]`` section (:class:`ServoSettings`, ``parse_servo``, the sampling check);
* ``plant``     -- motor, belt and bar as a two-mass system (:class:`DriveAxis`, belt stiffness);
* ``loop``      -- the drive's cascade controller: tuning, margins, the closed loop, its periodic response;
* ``accuracy``  -- the handover accuracy prediction (:class:`AccuracyResult`, ``strokeopt accuracy``);
* ``kernel``    -- the servo's term of the design's handover-accuracy constraint;
* ``tradeoff``  -- the highest stitch rate for each required accuracy (``strokeopt tradeoff``).

Their text and figures are in :mod:`strokeopt.report.servo`.
"""
