"""``python -m semkit`` = the ``semkit`` command."""
import sys

from .cli import main

sys.exit(main())
