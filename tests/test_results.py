import json
import math

import pytest

from motionlab.course.results import Chapter, ClaimFailed, failing_claims, load_results, results_path


@pytest.fixture
def build(monkeypatch, tmp_path):
    monkeypatch.setenv("MOTIONLAB_BUILD", str(tmp_path))
    return tmp_path


def test_metrics_and_claims_are_written(build, monkeypatch):
    monkeypatch.setenv("MOTIONLAB_PROFILE", "full")
    chapter = Chapter("04_motion_cell")
    chapter.metric("mcell.fid", 0.42, ci95=0.05)
    chapter.claim(
        "04.fid_beats_erd", value=0.42, threshold=1.37, op="<", text="Motion Cell FID is below ERD's"
    )
    data = json.loads(results_path().read_text())
    assert results_path() == build / "course" / "results.json"
    assert data["profile"] == "full"
    entry = data["notebooks"]["04_motion_cell"]
    assert entry["metrics"] == {"mcell.fid": 0.42, "mcell.fid.ci95": 0.05}
    claim = entry["claims"]["04.fid_beats_erd"]
    assert claim["holds"] is True and claim["threshold"] == 1.37 and claim["expected"] is True


def test_failing_claim_raises_in_full_profile_and_is_still_recorded(build, monkeypatch):
    monkeypatch.setenv("MOTIONLAB_PROFILE", "full")
    chapter = Chapter("03_variational_autoencoders")
    with pytest.raises(ClaimFailed, match="03.cvae_action_accuracy"):
        chapter.claim("03.cvae_action_accuracy", 0.5, 0.9, ">=", "CVAE samples are recognised")
    claim = load_results()["notebooks"]["03_variational_autoencoders"]["claims"]["03.cvae_action_accuracy"]
    assert claim["holds"] is False


def test_record_mode_checks_every_claim_and_names_the_failing_ones(build, monkeypatch):
    """``MOTIONLAB_CLAIMS=record`` (a claim × seed table needs every claim): no raise, the chapter goes on,
    and :func:`failing_claims` names what the course build then fails on; a known gap is not named."""
    monkeypatch.setenv("MOTIONLAB_PROFILE", "full")
    monkeypatch.setenv("MOTIONLAB_CLAIMS", "record")
    chapter = Chapter("08_contrastive_mode_discovery")
    assert not chapter.claim("08.a", 0.5, 0.9, ">=", "fails").holds
    assert chapter.claim("08.b", 1.0, 0.9, ">=", "holds").holds
    chapter.claim("08.c", 0.1, 0.9, ">=", "a known gap", expected=False, why="measured")
    assert failing_claims("08_contrastive_mode_discovery") == ["08.a"]
    monkeypatch.setenv("MOTIONLAB_CLAIMS", "sometimes")
    with pytest.raises(ValueError, match="MOTIONLAB_CLAIMS must be 'assert' or 'record'"):
        chapter.claim("08.d", 0.5, 0.9, ">=", "fails")


def test_failing_claim_is_only_recorded_in_quick_profile(build, monkeypatch):
    monkeypatch.setenv("MOTIONLAB_PROFILE", "quick")
    claim = Chapter("03_variational_autoencoders").claim("03.x", 0.5, 0.9, ">=", "text")
    assert not claim.holds
    assert results_path() == build / "course-quick" / "results.json"


def test_known_gap_needs_a_reason_and_does_not_raise(build, monkeypatch):
    monkeypatch.setenv("MOTIONLAB_PROFILE", "full")
    chapter = Chapter("07_masked_trajectory_completion")
    with pytest.raises(ValueError, match="why"):
        chapter.claim("07.x", 1.0, 3.0, ">=", "text", expected=False)
    claim = chapter.claim("07.x", 1.0, 3.0, ">=", "text", expected=False, why="too little data")
    assert not claim.holds and "known gap" in chapter.table()


def test_non_finite_values_are_rejected(build):
    chapter = Chapter("01_rotation_geometry")
    with pytest.raises(ValueError, match="geo.err"):
        chapter.metric("geo.err", math.nan)
    with pytest.raises(ValueError, match="01.c"):
        chapter.claim("01.c", math.inf, 1.0, "<", "text")
    with pytest.raises(ValueError, match="op"):
        chapter.claim("01.c", 0.0, 1.0, "==", "text")


def test_reopening_a_chapter_clears_its_old_numbers_but_not_others(build):
    Chapter("01_rotation_geometry").metric("a", 1.0)
    Chapter("02_skeletons_and_motion_data").metric("b", 2.0)
    Chapter("01_rotation_geometry")
    notebooks = load_results()["notebooks"]
    assert notebooks["01_rotation_geometry"]["metrics"] == {}
    assert notebooks["02_skeletons_and_motion_data"]["metrics"] == {"b": 2.0}


def test_results_of_another_profile_are_not_mixed(build, monkeypatch):
    monkeypatch.setenv("MOTIONLAB_PROFILE", "full")
    path = results_path()
    path.parent.mkdir(parents=True)
    path.write_text(json.dumps({"profile": "quick", "notebooks": {"old": {}}}))
    assert load_results()["notebooks"] == {}


def test_corrupt_results_file_is_reported(build):
    path = results_path()
    path.parent.mkdir(parents=True)
    path.write_text("{not json")
    with pytest.raises(ValueError, match="not valid JSON"):
        load_results()


def test_an_appendix_records_under_its_own_name(build):
    Chapter("04_motion_cell").metric("mcell.fid", 0.42)
    Chapter("04a_motion_cell_appendix").metric("mcell.audit", 1.5)
    notebooks = load_results()["notebooks"]
    assert notebooks["04a_motion_cell_appendix"]["metrics"] == {"mcell.audit": 1.5}
    assert notebooks["04_motion_cell"]["metrics"] == {"mcell.fid": 0.42}
