"""The servo axis: how far the bar is from its commanded position, and what accuracy costs.

Modules in data-flow order:

* ``settings``  -- the ``[servo]`` section (:class:`ServoSettings`, ``parse_servo``, the sampling check);
* ``plant``     -- motor, belt and bar as a two-mass system (:class:`DriveAxis`, belt stiffness);
* ``lti``       -- linear systems in numpy: state space, Padé delay, exact responses, loop margins;
* ``loop``      -- the drive's cascade controller: tuning, margins, the closed loop, its periodic response;
* ``accuracy``  -- the handover accuracy prediction (:class:`AccuracyResult`, ``strokeopt accuracy``);
* ``error_expression`` -- the form of a handover error term in the design's NLP (:class:`ErrorExpression`);
* ``table_term`` -- the full simulation's handover error as rows linear in the design's variables;
* ``kernel``    -- the servo's term of the design's handover-accuracy constraint (those rows in the NLP).

The trade-off of accuracy against stitch rate (``strokeopt tradeoff``) is a study: :mod:`strokeopt.studies.tradeoff`.

Their text and figures are in :mod:`strokeopt.report.servo`.
"""
