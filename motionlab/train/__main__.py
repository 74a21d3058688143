"""``python -m motionlab.train FAMILY ...`` (see :mod:`motionlab.train.cli`)."""

import sys

from motionlab.train.cli import main

sys.exit(main())
