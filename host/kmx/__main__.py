"""python3 -m kmx: the kmx command (kmx/cli.py)."""
import sys

from .cli import main

sys.exit(main())
