"""``python -m ionic_usd.cli``: the same command line as ``ionic-usd``."""

import sys

from ionic_usd.cli import main

sys.exit(main())
