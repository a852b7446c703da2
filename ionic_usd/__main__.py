"""``python -m ionic_usd``: the same command line as ``ionic-usd``."""

import sys

from ionic_usd.cli import main

sys.exit(main())
