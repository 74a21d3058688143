"""The applications on top of the library: the training command (:mod:`~motionlab.apps.training`, with the
chapters' families in :mod:`~motionlab.apps.families`) and chapter 09's common benchmark of the four
generators (:mod:`~motionlab.apps.comparison`). Nothing in the layers below imports from here."""
