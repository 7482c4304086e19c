"""``python -m hugger`` runs the ``hugger`` command."""
import sys

from .cli import main

sys.exit(main())
