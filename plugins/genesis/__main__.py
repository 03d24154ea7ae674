"""``python -m plugins.genesis DIR [module:function] [--out-dir OUTDIR]`` (:func:`.runner.main`)."""

import sys

from plugins.genesis.runner import main

sys.exit(main())
