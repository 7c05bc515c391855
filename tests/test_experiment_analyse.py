"""experiment-analyse on a database holding the paper's answers (Table III, Figs. 13-14)."""
from __future__ import annotations

import json
import random
from pathlib import Path

import numpy as np
import pytest

from test_experiment_stats import TABLE_III
from xsl_render.core.imageio import read_image
from xsl_render.core.psychophysics.analysis import analyse_answers
from xsl_render.core.psychophysics.plan import NO_REFERENCE, REFERENCE
from xsl_render.core.psychophysics.stimuli import StimulusPair
from xsl_render.core.psychophysics.store import ExperimentStore, read_answers

SCENE_NAMES = {"balls A": "balls_a", "balls B": "balls_b", "Lucy": "lucy", "road": "road",
               "road XSL": "road_xsl"}
CORRECT = {(SCENE_NAMES[scene], condition): correct
           for scene, condition, _, correct, _, _ in TABLE_III}


def events(condition: str, jitter: float = 0.0) -> dict:
    if condition == NO_REFERENCE:
        return {"first_on": 10.0, "first_off": 4010.0 + jitter, "second_on": 6010.0 + jitter,
                "second_off": 10010.0 + jitter, "answer_at": 11500.0}
    return {"on": 10.0, "off": 8010.0 + jitter, "answer_at": 9000.0}


def answer(store, plan, scene, condition, correct, jitter=0.0):
    gold = next(t.gold_position for t in plan.trials if t.scene == scene)
    a, b = ("first", "second") if condition == NO_REFERENCE else ("left", "right")
    other = b if gold == a else a
    # no reference asks for the worse image (right = not gold); reference for the most similar
    right = other if condition == NO_REFERENCE else gold
    store.record_answer(plan.participant_id, scene, right if correct else (other if right == gold else gold),
                        events(condition, jitter), page_hidden=False)


@pytest.fixture(scope="module")
def paper_db(tmp_path_factory) -> Path:
    """The paper's two experiments in one database: 48 participants alternating between the
    conditions on four scenes, then 24 with the reference condition on the XSL road."""
    path = tmp_path_factory.mktemp("paper") / "answers.sqlite"
    store = ExperimentStore(path, durable=False)
    scenes = ["balls_a", "balls_b", "lucy", "road"]
    store.sync_stimuli([StimulusPair(s, Path(f"{s}.gold.png"), Path(f"{s}.test.png"), 8, 8,
                                     "0" * 64, "1" * 64) for s in scenes + ["road_xsl"]])
    rng = random.Random(11)
    seen = {NO_REFERENCE: 0, REFERENCE: 0}
    for i in range(48):
        plan = store.register(f"e1-{i:02d}", "18-24", False, {}, scenes,
                              (NO_REFERENCE, REFERENCE), rng)
        k = seen[plan.condition]
        seen[plan.condition] += 1
        for scene in scenes:
            answer(store, plan, scene, plan.condition, k < CORRECT[(scene, plan.condition)],
                   jitter=(-1) ** i * 3.0)
    for i in range(24):
        plan = store.register(f"e2-{i:02d}", "25-34", True, {}, ["road_xsl"], (REFERENCE,), rng)
        answer(store, plan, "road_xsl", REFERENCE, i < CORRECT[("road_xsl", REFERENCE)])
    store.close()
    return path


def test_cli_json_reproduces_table_iii(paper_db, cli):
    result = cli("experiment-analyse", paper_db, "--json", timeout=60)
    assert result.returncode == 0, result.stderr
    report = json.loads(result.stdout)
    assert report["participants"] == 72 and report["trials"] == 4 * 48 + 24
    cells = {(c["scene"], c["condition"]): c for c in report["cells"]}
    assert set(cells) == set(CORRECT)
    for scene, condition, percent, correct, chi2, p in TABLE_III:
        cell = cells[(SCENE_NAMES[scene], condition)]
        assert (cell["n"], cell["correct"], cell["incorrect"]) == (24, correct, 24 - correct)
        assert round(cell["percent_correct"]) == percent
        assert round(cell["chi2"], len(chi2.partition(".")[2])) == pytest.approx(float(chi2))
        assert round(cell["p"], len(p.partition(".")[2])) == pytest.approx(float(p))
        assert cell["timing"] == {"worst_error_ms": pytest.approx(3.0 if scene != "road XSL" else 0.0),
                                  "off_timing": 0, "page_hidden": 0}


def test_cli_table_and_chart(paper_db, cli, tmp_path):
    chart = tmp_path / "fig13.png"
    result = cli("experiment-analyse", paper_db, "--chart", chart, timeout=120)
    assert result.returncode == 0, result.stderr
    assert "chi2(1, N = 24) = 16.67, p < 0.001" in result.stdout
    assert "chi2(1, N = 24) = 0.167, p = 0.683" in result.stdout
    assert "72 participants" in result.stdout
    image = read_image(chart)
    assert image.shape[0] > 200 and image.shape[1] > 400
    # the bars are drawn in the two condition colours
    rgb = np.round(image[..., :3] * 255).astype(int).reshape(-1, 3)
    for colour in ((0x7f, 0x9f, 0xbf), (0x1f, 0x3f, 0x6f)):
        assert (np.abs(rgb - colour).max(axis=1) <= 2).sum() > 500


def test_off_timing_trials_are_counted_and_can_be_left_out(tmp_path):
    path = tmp_path / "a.sqlite"
    store = ExperimentStore(path, durable=False)
    store.sync_stimuli([StimulusPair("s", Path("s.gold.png"), Path("s.test.png"), 8, 8, "0" * 64, "1" * 64)])
    rng = random.Random(2)
    for i, jitter in enumerate([0.0, 120.0, 5.0]):
        plan = store.register(f"p{i}", "18-24", False, {}, ["s"], (REFERENCE,), rng)
        answer(store, plan, "s", REFERENCE, True, jitter)
    store.close()
    rows = read_answers(path)
    kept = analyse_answers(rows, timing_tolerance_ms=50.0)
    assert kept["cells"][0]["n"] == 3 and kept["cells"][0]["timing"]["off_timing"] == 1
    assert kept["cells"][0]["timing"]["worst_error_ms"] == pytest.approx(120.0)
    dropped = analyse_answers(rows, timing_tolerance_ms=50.0, exclude_off_timing=True)
    assert dropped["cells"][0]["n"] == 2 and dropped["excluded"] == 1


@pytest.mark.parametrize("case", ["empty", "garbage", "missing", "bad-chart"])
def test_cli_bad_input_is_exit_2(tmp_path, cli, case, paper_db):
    db = tmp_path / "a.sqlite"
    args = []
    if case == "empty":
        ExperimentStore(db).close()
    elif case == "garbage":
        db.write_text("not a database at all " * 50)
    elif case == "bad-chart":
        db = paper_db
        args = ["--chart", tmp_path / "chart.svgz"]
    result = cli("experiment-analyse", db, *args, timeout=60)
    assert result.returncode == 2, result.stderr
    assert result.stderr.startswith("xsl-render: error:") and result.stderr.count("\n") == 1


def test_the_summary_counts_every_trial_excluded_as_off_timing(tmp_path):
    """Issue 15, point 7: a cell whose every trial was excluded left its off-timing trials out
    of the summary, which then said "1 trials off ... 3 excluded"."""
    from xsl_render.core.psychophysics.analysis import format_report

    path = tmp_path / "a.sqlite"
    store = ExperimentStore(path, durable=False)
    store.sync_stimuli([StimulusPair(s, Path(f"{s}.gold.png"), Path(f"{s}.test.png"), 8, 8, "0" * 64, "1" * 64)
                        for s in ("late", "ok")])
    rng = random.Random(5)
    for i in range(3):
        plan = store.register(f"p{i}", "18-24", False, {}, ["late", "ok"], (REFERENCE,), rng)
        answer(store, plan, "late", REFERENCE, True, 200.0)            # every one off timing
        answer(store, plan, "ok", REFERENCE, i > 0, 100.0 if i == 0 else 0.0)
    store.close()
    report = analyse_answers(read_answers(path), timing_tolerance_ms=50.0, exclude_off_timing=True)
    assert [cell["scene"] for cell in report["cells"]] == ["ok"]
    assert report["excluded"] == 4 and report["timing"] == {"worst_error_ms": pytest.approx(200.0),
                                                             "off_timing": 4, "page_hidden": 0}
    summary = format_report(report).splitlines()[-1]
    assert "worst deviation 200.0 ms" in summary and "4 trials off" in summary and "4 excluded" in summary
