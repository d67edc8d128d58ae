"""``python -m hsgran``: the same as the ``hsgran`` command (layer 6)."""

import sys

from hsgran.cli import main

sys.exit(main())
