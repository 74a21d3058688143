"""Claims over training seeds (:mod:`motionlab.course.seeds`): recorded from course builds, shown per
chapter, and complete for the shipped course."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from motionlab.apps import reference as command
from motionlab.course import seeds
from motionlab.paths import REPO_ROOT


def _build(tmp_path: Path, seed: int, values: dict[str, float], profile: str = "full") -> Path:
    folder = tmp_path / f"seed{seed}"
    (folder / "course").mkdir(parents=True)
    claims = {
        name: {"value": value, "op": "<", "threshold": 1.0, "expected": name != "04.gap", "text": name}
        for name, value in values.items()
    }
    results = {
        "profile": profile,
        "base_seed": seed,
        "models": "reference" if seed == 0 else "retrained",
        "numerics": {},
        "torch": "2.13.0",
        "notebooks": {"04_motion_cell": {"claims": claims}},
    }
    (folder / "course" / "results.json").write_text(json.dumps(results))
    return folder


def _recorded(values: dict[str, float]) -> dict[str, object]:
    """A claim of the recorded table with its values per seed."""
    return {"op": "<", "threshold": 1.0, "expected": True, "text": "", "values": values}


def test_claims_are_collected_per_seed_and_shown_per_chapter(tmp_path: Path) -> None:
    builds = {
        0: _build(tmp_path, 0, {"04.small": 0.5, "04.gap": 2.0, "04a.audit": 0.1}),
        1: _build(tmp_path, 1, {"04.small": 1.5, "04.gap": 3.0, "04a.audit": 0.2}),
        2: _build(tmp_path, 2, {"04.small": 0.25, "04.gap": 0.5, "04a.audit": 0.3}),
    }
    record = seeds.collect(builds)
    assert record["claims"]["04.small"]["values"] == {"0": 0.5, "1": 1.5, "2": 0.25}
    assert record["seeds"]["1"]["models"] == "retrained"
    path = seeds.save(record, tmp_path / "claims.json")
    table = seeds.chapter_table("04", path)
    assert "| `04.small` | < 1 | 0.5 | 1.5 ✗ | 0.25 | **fails** |" in table
    assert "| `04.gap` | < 1 | 2 ✗ | 3 ✗ | 0.5 | known gap |" in table
    assert "| `04a.audit` | < 1 | 0.1 | 0.2 | 0.3 | holds |" in table  # the appendix's claims too
    assert seeds.chapter_table("05", path) == "No claim of chapter 05 is recorded over training seeds."
    del record["claims"]["04a.audit"]["values"]["2"]  # a build that did not run the appendix
    table = seeds.chapter_table("04", seeds.save(record, path))
    assert "| `04a.audit` | < 1 | 0.1 | 0.2 | – | holds on the 2 seeds measured |" in table


def test_builds_of_some_chapters_update_their_claims_and_keep_the_rest(tmp_path: Path) -> None:
    """A model family retrained: builds of the chapters that use it replace those chapters' values (a claim
    the chapter no longer makes loses them) and leave the other chapters' as they were."""
    base = seeds.collect({0: _build(tmp_path, 0, {"04.small": 0.5, "04.dropped": 0.1})})
    base["claims"]["05.other"] = _recorded({"0": 0.7})
    again = _build(tmp_path / "again", 0, {"04.small": 0.25, "04.new": 0.3})
    record = seeds.collect({0: again}, base)
    assert record["claims"]["04.small"]["values"] == {"0": 0.25} and record["claims"]["04.new"]["values"] == {
        "0": 0.3
    }
    assert "04.dropped" not in record["claims"] and record["claims"]["05.other"]["values"] == {"0": 0.7}
    assert base["claims"]["04.small"]["values"] == {"0": 0.5}  # the base record itself is left alone


def test_an_update_can_take_some_chapters_of_a_build_folder(tmp_path: Path) -> None:
    """A build folder keeps the results of every chapter it has built: ``chapters`` takes only those named
    (with their appendices) and leaves the others' recorded values alone."""
    base = seeds.collect({1: _build(tmp_path, 1, {"04.small": 0.5})})
    base["claims"]["06.flow"] = _recorded({"1": 0.7})
    folder = _build(tmp_path / "again", 1, {"04.small": 0.25})  # an earlier build of chapter 04 left it there
    results = json.loads((folder / "course" / "results.json").read_text())
    claim = results["notebooks"]["04_motion_cell"]["claims"]["04.small"]
    results["notebooks"]["06_moglow"] = {"claims": {"06.flow": {**claim, "value": 0.1}}}
    results["notebooks"]["06a_moglow_appendix"] = {"claims": {"06a.audit": {**claim, "value": 0.2}}}
    (folder / "course" / "results.json").write_text(json.dumps(results))
    values = {
        name: c["values"] for name, c in seeds.collect({1: folder}, base, chapters=("06",))["claims"].items()
    }
    assert values == {"04.small": {"1": 0.5}, "06.flow": {"1": 0.1}, "06a.audit": {"1": 0.2}}
    assert seeds.collect({1: folder}, base)["claims"]["04.small"]["values"] == {"1": 0.25}  # without: all


def test_a_build_that_is_not_the_seed_given_is_refused(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="seed 1: .* was built with base seed 0"):
        seeds.collect({1: _build(tmp_path, 0, {"04.small": 0.5})})
    with pytest.raises(ValueError, match="is a 'quick' build"):
        seeds.collect({2: _build(tmp_path, 2, {"04.small": 0.5}, profile="quick")})
    with pytest.raises(FileNotFoundError, match="seed 3: .*results.json does not exist"):
        seeds.collect({3: tmp_path / "nowhere"})


def test_the_command_records_the_table_and_refuses_bad_arguments(tmp_path, monkeypatch, capsys) -> None:
    monkeypatch.setattr(seeds, "SEED_CLAIMS_PATH", tmp_path / "claims.json")
    build = _build(tmp_path, 0, {"04.small": 0.5})
    assert command.main(["seeds", f"0={build}"]) == 0
    assert "1 claims over seeds 0 written to" in capsys.readouterr().out
    assert json.loads((tmp_path / "claims.json").read_text())["claims"]["04.small"]["values"] == {"0": 0.5}
    update = _build(tmp_path / "update", 0, {"04.small": 0.25})
    assert command.main(["seeds", "--update", f"0={update}"]) == 0
    assert json.loads((tmp_path / "claims.json").read_text())["claims"]["04.small"]["values"] == {"0": 0.25}
    assert command.main(["seeds", f"1={build}"]) == 1
    assert "error: seed 1:" in capsys.readouterr().err
    assert command.main(["seeds", "--update", "--chapters", "04", f"0={build}"]) == 0
    assert json.loads((tmp_path / "claims.json").read_text())["claims"]["04.small"]["values"] == {"0": 0.5}
    for argv, message in (
        (["seeds", "--chapters", "04", f"0={build}"], "--chapters limits an --update"),
        (["seeds", "--update", "--chapters", "04,6", f"0={build}"], "expected chapters' two-digit numbers"),
    ):
        with pytest.raises(SystemExit) as exit_info:
            command.main(argv)
        assert exit_info.value.code == 2 and message in capsys.readouterr().err
    with pytest.raises(SystemExit) as exit_info:
        command.main(["seeds", "one=/tmp"])
    assert exit_info.value.code == 2 and "expected SEED=BUILD" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exit_info:
        command.main(["export", str(build), "--replace", "mdm"])
    assert (
        exit_info.value.code == 2 and "--replace names runs of a --partial build" in capsys.readouterr().err
    )


def test_every_claim_of_the_model_chapters_is_recorded_over_three_seeds() -> None:
    """The shipped table covers each claim chapters 03-11 and their appendices make, for seeds 0, 1 and 2."""
    record = json.loads(seeds.SEED_CLAIMS_PATH.read_text(encoding="utf-8"))
    assert sorted(record["seeds"]) == ["0", "1", "2"]
    named = set()
    for path in sorted((REPO_ROOT / "notebooks").glob("[01][0-9]*_*.ipynb")):
        if not "03" <= path.name[:2] <= "11":
            continue
        source = "\n".join("".join(cell["source"]) for cell in json.loads(path.read_text())["cells"])
        named |= set(re.findall(r'claim\(\s*"(\d\da?\.[a-z0-9_]+)"', source))
    missing = sorted(
        name for name in named if set(record["claims"].get(name, {}).get("values", {})) != {"0", "1", "2"}
    )
    assert named and not missing, f"claims without values for seeds 0, 1 and 2: {missing}"
