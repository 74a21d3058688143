"""Packages with lazy public names (``motionlab.lazy``): a name's module is imported on first use, and only
it."""

import subprocess
import sys

import pytest

import motionlab.exercises as exercises

#: Run in a fresh interpreter, so that no other test has imported the modules yet.
FIRST_USE = """
import sys
import motionlab.exercises as exercises
before = "motionlab.exercises.diffusion" in sys.modules, "motionlab.exercises.rotations" in sys.modules
exercises.check_slerp
after = "motionlab.exercises.diffusion" in sys.modules, "motionlab.exercises.rotations" in sys.modules
print(before, after)
"""


def test_a_name_imports_its_own_module_on_first_use_and_no_other():
    shown = subprocess.run([sys.executable, "-c", FIRST_USE], capture_output=True, text=True, check=True)
    assert shown.stdout.split("\n")[0] == "(False, False) (False, True)"


def test_every_listed_name_resolves_and_dir_lists_them():
    assert all(callable(getattr(exercises, name)) for name in exercises.__all__)
    assert set(exercises.__all__) <= set(dir(exercises))


def test_an_unknown_name_is_an_attribute_error_naming_it():
    with pytest.raises(AttributeError, match="module 'motionlab.exercises' has no attribute 'check_nothing'"):
        exercises.check_nothing  # noqa: B018
