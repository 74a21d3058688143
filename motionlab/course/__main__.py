"""``python -m motionlab.course``: execute every chapter and build the report (:mod:`.run`)."""

from motionlab.course.run import main

raise SystemExit(main())
