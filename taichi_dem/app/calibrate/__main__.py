"""``python -m taichi_dem.app.calibrate SPEC.toml --out DIR``: the same as ``taichi-dem calibrate``."""
import sys

from . import main

sys.exit(main())
