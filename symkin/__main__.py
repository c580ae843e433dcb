"""python -m symkin: the symkin command."""

import sys

from symkin.cli import main

sys.exit(main())
