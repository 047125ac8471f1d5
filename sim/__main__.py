"""``python -m sim`` = ``gbmsim``."""
from .cli import main

raise SystemExit(main())
