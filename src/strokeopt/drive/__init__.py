"""The drive: from the load motion to the motor, and which motor and pulley to buy.

Modules in data-flow order:

- ``transmission.py``  motor angle -> load position (belt pulley, crank, screw and lever); the
  toothed-pulley geometry (pitch diameter of a profile and tooth count)
- ``catalogue.py``     servo motors, steppers (pull-out curve), pulleys, belts and their catalogue files
- ``load.py``          the load (mass, gravity, load forces) and the motor torque it asks for
- ``checks.py``        the sizing checks of one motor and transmission over a cycle, the belt load
- ``spec.py``          the ``[drive]`` section of a problem file (``DriveSpec``)
- ``sizing.py``        every catalogue motor with every pulley, ranked; highest stitch rate;
  the continuous pulley radius
"""
