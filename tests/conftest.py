"""Shared test settings: quick profile, one torch thread."""

import os

os.environ.setdefault("MOTIONLAB_PROFILE", "quick")

from motionlab import config  # noqa: E402

config.set_threads()
