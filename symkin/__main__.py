"""python -m symkin: the symkin command."""

import sys

from symkin.cli.main import main

sys.exit(main())
