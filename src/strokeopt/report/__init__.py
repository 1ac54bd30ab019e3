"""Every text table and every figure; computing packages return data, this package prints and draws it.

* format.py   plain-text tables (JSON and the number format come from :mod:`strokeopt.io.plain`)
* figures.py  what every figure shares (the problem's coordinates, dwell bands; the printed width, titles
              wrapped inside their figure, legends beside the data)
* machine.py  what the problem has (output, transmission, servo or stepper, handover, kind of scene): the
              reports' sections and words follow it
* motion.py, drive.py, design.py, contact.py, servo.py  one module per area, in data-flow order
* html.py     one self-contained HTML page (sections, tables with data-key/data-value, inline SVG, print CSS)
* design_report.py, compare_report.py  the HTML design report of a design and the comparison of designs
"""
