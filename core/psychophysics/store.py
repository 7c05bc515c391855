"""The answers of a 2AFC experiment in SQLite, written as they come.

Every registration and every answer is its own committed transaction, so a closed browser
or a stopped server loses nothing already answered. The schema makes the experiment's rules
hold even against a misbehaving page: a participant id registers once (primary key), has one
trial per scene (unique), and answers each trial once (primary key of ``answers``).
"""
from __future__ import annotations

import json
import math
import os
import random
import re
import sqlite3
import threading
from dataclasses import dataclass
from datetime import datetime, timezone
from pathlib import Path

from ..errors import InputError, SettingError, verbatim
from .plan import (AGE_RANGES, NO_REFERENCE, POSITIONS, Trial, choose_condition,
                   durations_from_events, gold_first_scenes, is_correct, plan_trials)
from .stimuli import StimulusPair

SCHEMA_VERSION = "1"
_PARTICIPANT_ID = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_-]{0,63}\Z")

_SCHEMA = """
CREATE TABLE IF NOT EXISTS meta (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS stimuli (
    scene TEXT PRIMARY KEY, width INTEGER NOT NULL, height INTEGER NOT NULL,
    gold_sha256 TEXT NOT NULL, test_sha256 TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS participants (
    participant_id TEXT PRIMARY KEY, registered_at TEXT NOT NULL,
    age_range TEXT NOT NULL, vision_corrected INTEGER NOT NULL CHECK (vision_corrected IN (0, 1)),
    condition TEXT NOT NULL, index_in_condition INTEGER NOT NULL, display_json TEXT NOT NULL,
    UNIQUE (condition, index_in_condition));
CREATE TABLE IF NOT EXISTS trials (
    participant_id TEXT NOT NULL REFERENCES participants (participant_id),
    trial_order INTEGER NOT NULL, scene TEXT NOT NULL REFERENCES stimuli (scene),
    gold_position TEXT NOT NULL,
    PRIMARY KEY (participant_id, trial_order), UNIQUE (participant_id, scene));
CREATE TABLE IF NOT EXISTS answers (
    participant_id TEXT NOT NULL, scene TEXT NOT NULL, condition TEXT NOT NULL,
    choice TEXT NOT NULL, correct INTEGER NOT NULL CHECK (correct IN (0, 1)),
    answered_at TEXT NOT NULL, response_ms REAL, page_hidden INTEGER NOT NULL,
    durations_json TEXT NOT NULL, events_json TEXT NOT NULL,
    PRIMARY KEY (participant_id, scene),
    FOREIGN KEY (participant_id, scene) REFERENCES trials (participant_id, scene));
"""


class Conflict(Exception):
    """The request contradicts what is stored: a second registration or a second answer."""


class NotFound(Exception):
    """No such participant or trial."""


@dataclass(frozen=True)
class ParticipantPlan:
    participant_id: str
    condition: str
    trials: list[Trial]
    answered: frozenset[str]


def _is_finite_number(value) -> bool:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:               # an int past float's range
        return False


def _now() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="milliseconds")


class ExperimentStore:
    """The experiment database, shared by the server's request threads."""

    def __init__(self, path: str | os.PathLike, durable: bool = True):
        """Open or create the database at ``path``.

        ``durable`` (the default, and what the server uses) has SQLite flush every commit to
        the disk before it returns, so an answer acknowledged to the page survives even a
        power cut. ``False`` skips the flushes, for building databases in bulk (tests).
        """
        self.path = Path(path)
        try:
            self._db = sqlite3.connect(str(self.path), isolation_level=None,
                                       check_same_thread=False, timeout=10.0)
            self._db.execute("PRAGMA foreign_keys = ON")
            self._db.execute(f"PRAGMA synchronous = {'FULL' if durable else 'OFF'}")
            self._db.executescript(_SCHEMA)
            self._db.execute("INSERT OR IGNORE INTO meta VALUES ('schema_version', ?)",
                             (SCHEMA_VERSION,))
        except sqlite3.DatabaseError as error:
            raise InputError(f"cannot use {self.path} as the answers database: {error}") from None
        self._lock = threading.Lock()

    def close(self) -> None:
        self._db.close()

    def _transaction(self):
        return _Transaction(self._db, self._lock)

    def sync_stimuli(self, pairs: list[StimulusPair]) -> None:
        """Record the stimuli; refuse a scene whose images changed since answers were taken."""
        with self._transaction() as db:
            for pair in pairs:
                row = db.execute("SELECT gold_sha256, test_sha256, width, height FROM stimuli "
                                 "WHERE scene = ?", (pair.scene,)).fetchone()
                if row is None:
                    db.execute("INSERT INTO stimuli VALUES (?, ?, ?, ?, ?)",
                               (pair.scene, pair.width, pair.height, pair.gold_sha256,
                                pair.test_sha256))
                elif tuple(row) != (pair.gold_sha256, pair.test_sha256, pair.width, pair.height):
                    raise SettingError(f"the images of scene '{verbatim(pair.scene)}' changed "
                                       "since {db.value} recorded them; start a new answers "
                                       "database ({db.name})", db=self.path)

    def register(self, participant_id: str, age_range: str, vision_corrected: bool,
                 display: dict, scenes: list[str], allowed_conditions: tuple[str, ...],
                 rng: random.Random) -> ParticipantPlan:
        """Register a participant, assign a condition and a counterbalanced trial plan.

        Raises InputError for invalid metadata and Conflict for an id already registered.
        """
        if not isinstance(participant_id, str) or not _PARTICIPANT_ID.match(participant_id):
            raise InputError("participant id: 1-64 letters, digits, '_' or '-'")
        if age_range not in AGE_RANGES:
            raise InputError(f"age range must be one of {', '.join(AGE_RANGES)}")
        if not isinstance(vision_corrected, bool):
            raise InputError("vision corrected must be yes or no")
        if not isinstance(display, dict):
            raise InputError("display must be an object")
        with self._transaction() as db:
            if db.execute("SELECT 1 FROM participants WHERE participant_id = ?",
                          (participant_id,)).fetchone():
                raise Conflict(f"participant {participant_id} is already registered")
            counts = dict(db.execute("SELECT condition, COUNT(*) FROM participants GROUP BY condition"))
            condition = choose_condition(counts, allowed_conditions)
            index = counts.get(condition, 0)
            partner = None
            if index % 2 == 1:   # second of a counterbalancing block: mirror the first
                first_of_block = db.execute(
                    "SELECT t.scene, t.gold_position FROM trials t JOIN participants p "
                    "USING (participant_id) WHERE p.condition = ? AND p.index_in_condition = ?",
                    (condition, index - 1)).fetchall()
                partner = {scene: pos == POSITIONS[condition][0] for scene, pos in first_of_block}
            gold_first = gold_first_scenes(scenes, partner, rng)
            trials = plan_trials(scenes, condition, gold_first, rng)
            db.execute("INSERT INTO participants VALUES (?, ?, ?, ?, ?, ?, ?)",
                       (participant_id, _now(), age_range, int(vision_corrected), condition,
                        index, json.dumps(display, sort_keys=True)))
            db.executemany("INSERT INTO trials VALUES (?, ?, ?, ?)",
                           [(participant_id, t.order, t.scene, t.gold_position) for t in trials])
        return ParticipantPlan(participant_id, condition, trials, frozenset())

    def plan(self, participant_id: str) -> ParticipantPlan:
        """A registered participant's condition, trials and the scenes already answered."""
        with self._transaction() as db:
            row = db.execute("SELECT condition FROM participants WHERE participant_id = ?",
                             (participant_id,)).fetchone()
            if row is None:
                raise NotFound(f"no participant {participant_id}")
            trials = [Trial(order, scene, gold) for order, scene, gold in db.execute(
                "SELECT trial_order, scene, gold_position FROM trials WHERE participant_id = ? "
                "ORDER BY trial_order", (participant_id,))]
            answered = frozenset(scene for (scene,) in db.execute(
                "SELECT scene FROM answers WHERE participant_id = ?", (participant_id,)))
        return ParticipantPlan(participant_id, row[0], trials, answered)

    def record_answer(self, participant_id: str, scene: str, choice: str,
                      events: dict, page_hidden: bool) -> None:
        """Store one answer with the page's display time stamps, committed at once.

        Raises NotFound for an unknown trial, Conflict for a trial already answered and
        InputError for an impossible choice or malformed time stamps.
        """
        if not isinstance(events, dict):
            raise InputError("events must be an object of time stamps")
        with self._transaction() as db:
            row = db.execute(
                "SELECT p.condition, t.gold_position FROM trials t JOIN participants p "
                "USING (participant_id) WHERE participant_id = ? AND t.scene = ?",
                (participant_id, scene)).fetchone()
            if row is None:
                raise NotFound(f"participant {participant_id} has no trial for scene {scene}")
            condition, gold_position = row
            if choice not in POSITIONS[condition]:
                raise InputError(f"answer must be {' or '.join(POSITIONS[condition])}")
            try:
                durations = durations_from_events(condition, events)
            except ValueError as error:
                raise InputError(f"display time stamps: {error}") from None
            # Response time from the end of the last stimulus to the click, when the page sent it.
            answer_at = events.get("answer_at")
            last_off = float(events["second_off" if condition == NO_REFERENCE else "off"])
            response_ms = float(answer_at) - last_off if _is_finite_number(answer_at) else None
            stamps = {name: float(value) for name, value in events.items()
                      if isinstance(name, str) and _is_finite_number(value)}
            if db.execute("SELECT 1 FROM answers WHERE participant_id = ? AND scene = ?",
                          (participant_id, scene)).fetchone():
                raise Conflict(f"participant {participant_id} already answered scene {scene}")
            db.execute("INSERT INTO answers VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                       (participant_id, scene, condition, choice,
                        int(is_correct(condition, gold_position, choice)), _now(), response_ms,
                        int(bool(page_hidden)), json.dumps(durations),
                        json.dumps(stamps, sort_keys=True)))


class _Transaction:
    """``BEGIN IMMEDIATE`` ... ``COMMIT`` under the store's lock; ROLLBACK on any error."""

    def __init__(self, db: sqlite3.Connection, lock: threading.Lock):
        self._db, self._lock = db, lock

    def __enter__(self) -> sqlite3.Connection:
        self._lock.acquire()
        try:
            self._db.execute("BEGIN IMMEDIATE")
        except BaseException:
            self._lock.release()
            raise
        return self._db

    def __exit__(self, kind, value, traceback) -> None:
        try:
            self._db.execute("COMMIT" if kind is None else "ROLLBACK")
        finally:
            self._lock.release()


@dataclass(frozen=True)
class AnswerRow:
    participant_id: str
    scene: str
    condition: str
    correct: bool
    page_hidden: bool
    durations: dict[str, float]


def read_answers(path: str | os.PathLike) -> list[AnswerRow]:
    """Every stored answer of an experiment database, opened read-only."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"no such answers database: {path}")
    try:
        db = sqlite3.connect(f"{path.resolve().as_uri()}?mode=ro", uri=True)
        try:
            rows = db.execute("SELECT participant_id, scene, condition, correct, page_hidden, "
                              "durations_json FROM answers ORDER BY scene, condition, "
                              "participant_id").fetchall()
        finally:
            db.close()
    except sqlite3.DatabaseError as error:
        raise InputError(f"{path} is not an experiment database: {error}") from None
    return [AnswerRow(pid, scene, condition, bool(correct), bool(hidden), json.loads(durations))
            for pid, scene, condition, correct, hidden, durations in rows]
