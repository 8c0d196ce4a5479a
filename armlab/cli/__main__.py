"""`python -m armlab.cli` runs the `armlab` command."""

import sys

from armlab.cli import main

sys.exit(main())
