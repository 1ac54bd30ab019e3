"""``python -m strokeopt``: the same as the ``strokeopt`` command."""

import sys

from .cli.main import main

sys.exit(main())
