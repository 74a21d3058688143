"""The course's own tooling, apart from the science: executing the chapters and building the report.

Modules: :mod:`~motionlab.course.run` (``make course``: execute every chapter, write ``build/course/``),
:mod:`~motionlab.course.chapters` (the chapters and their appendices: numbers, course order),
:mod:`~motionlab.course.stats` (how long each chapter is, against its limits),
:mod:`~motionlab.course.kernel` (executing one notebook in a kernel that is watched for hangs),
:mod:`~motionlab.course.results` (the claims and metrics a chapter records: ``results.json``),
:mod:`~motionlab.course.report` (the report's front page), :mod:`~motionlab.course.assets` (the report's
scripts and fonts, offline), :mod:`~motionlab.course.browser` (the built report checked in Chromium),
:mod:`~motionlab.course.stress` (executing the chapters many times to find hangs) and
:mod:`~motionlab.course.logs` (running ``make test``/``make course`` with their output kept).

Nothing is imported here, so the light commands (``python -m motionlab.course.logs``) stay quick.
"""
