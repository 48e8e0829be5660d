"""``python -m ctxmodels.cli``: the ``ctxmodels`` command."""
import sys

from . import main

sys.exit(main())
