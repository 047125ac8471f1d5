"""``python -m gbmgen``: the same as the ``gbmgen`` console script."""
import sys

from .cli import main

sys.exit(main())
