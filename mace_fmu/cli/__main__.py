"""``python -m mace_fmu.cli``: the same as the ``mace-fmu`` command."""

import sys

from mace_fmu.cli import main

sys.exit(main())
