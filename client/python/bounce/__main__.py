"""`python3 -m bounce`: the command-line client (bounce.cli)."""

import sys

from .cli import main

sys.exit(main())
