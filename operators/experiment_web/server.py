"""The 2AFC experiment as a small local web app (standard library ``http.server``).

The page (``page/``) runs the procedures; this server hands it the participant's
plan, serves the stimuli and stores every answer in SQLite the moment it arrives.

Only what is in two fixed tables is ever served: the page's own files, and the stimuli
scanned at start, under random URLs (``/stimuli/<token>.png``) that say nothing about which
image is the gold standard. No part of a request path is ever joined to a file-system path,
so nothing outside the stimuli folder can be reached however the path is spelt.
"""
from __future__ import annotations

import errno
import json
import os
import random
import secrets
import sys
import traceback
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from urllib.parse import unquote, urlsplit

from ...core.errors import InputError
from ...core.psychophysics.plan import (AGE_RANGES, NO_REFERENCE, POSITIONS, QUESTIONS, TIMINGS_MS)
from ...core.psychophysics.stimuli import StimulusPair
from ...core.psychophysics.store import Conflict, ExperimentStore, NotFound, ParticipantPlan

PAGE_DIR = Path(__file__).resolve().parent / "page"
PAGE_FILES = {
    "/": ("index.html", "text/html; charset=utf-8"),
    "/experiment.js": ("experiment.js", "text/javascript; charset=utf-8"),
    "/experiment.css": ("experiment.css", "text/css; charset=utf-8"),
}
MAX_BODY_BYTES = 64 * 1024
#: Seconds a connection may stay silent (a request line, headers, a body shorter than its
#: Content-Length) before its thread gives up on it.
REQUEST_TIMEOUT_S = 10.0
#: How deeply a request's JSON may nest: the page sends two levels.
MAX_JSON_DEPTH = 8
#: Digits an integer in a request may have: the page's time stamps are milliseconds.
MAX_INT_DIGITS = 18


class ExperimentServer(ThreadingHTTPServer):
    """The HTTP server with the experiment's state: stimuli, their URLs, the store."""

    daemon_threads = True

    store: ExperimentStore

    def __init__(self, address: tuple[str, int], pairs: list[StimulusPair],
                 conditions: tuple[str, ...], log=None, request_timeout: float = REQUEST_TIMEOUT_S):
        self.request_timeout = request_timeout
        self.pairs = {pair.scene: pair for pair in pairs}
        self.conditions = conditions
        self.log = log or sys.stdout
        self.rng = random.Random(secrets.randbits(64))
        # Every image is read once now: what is shown is exactly what was hashed at start.
        # The reference image is the gold standard under a URL of its own.
        self.stimulus_urls: dict[tuple[str, str], str] = {}
        self.stimulus_bytes: dict[str, bytes] = {}
        for pair in pairs:
            for use, role in (("gold", "gold"), ("test", "test"), ("reference", "gold")):
                url = f"/stimuli/{secrets.token_urlsafe(12)}.png"
                self.stimulus_urls[(pair.scene, use)] = url
                self.stimulus_bytes[url] = pair.path(role).read_bytes()
        self.page_bytes = {route: ((PAGE_DIR / name).read_bytes(), mime)
                           for route, (name, mime) in PAGE_FILES.items()}
        try:
            super().__init__(address, ExperimentHandler)
        except OSError as error:
            in_use = error.errno in (errno.EADDRINUSE, getattr(errno, "WSAEADDRINUSE", None))
            reason = "is in use" if in_use else f"cannot be opened ({error.strerror or error})"
            raise InputError(f"port {address[1]} on {address[0]} {reason}; "
                             "choose another with --port") from None

    @property
    def url(self) -> str:
        host, port = self.server_address[:2]
        return f"http://{'127.0.0.1' if host in ('0.0.0.0', '') else host}:{port}/"

    def config(self) -> dict:
        return {"conditions": list(self.conditions), "age_ranges": list(AGE_RANGES),
                "scenes": len(self.pairs)}

    def plan_json(self, plan: ParticipantPlan) -> dict:
        """The participant's plan as the page needs it: image URLs in display order, never
        which of them is the gold standard."""
        condition = plan.condition
        trials = []
        for trial in plan.trials:
            pair = self.pairs.get(trial.scene)
            if pair is None:          # a scene removed from the folder since registration
                continue
            gold_url = self.stimulus_urls[(trial.scene, "gold")]
            test_url = self.stimulus_urls[(trial.scene, "test")]
            a, b = POSITIONS[condition]
            images = ({a: gold_url, b: test_url} if trial.gold_position == a
                      else {a: test_url, b: gold_url})
            if condition != NO_REFERENCE:
                images["reference"] = self.stimulus_urls[(trial.scene, "reference")]
            trials.append({"scene": trial.scene, "width": pair.width, "height": pair.height,
                           "answered": trial.scene in plan.answered, "images": images})
        return {"participant_id": plan.participant_id, "condition": condition,
                "question": QUESTIONS[condition], "answers": list(POSITIONS[condition]),
                "timings_ms": TIMINGS_MS[condition], "trials": trials}

    def handle_error(self, request, client_address) -> None:
        """One line instead of socketserver's traceback; a browser that went away while we
        answered (page closed or reloaded) is normal and what it sent is already stored."""
        kind, error, _ = sys.exc_info()
        if isinstance(error, ConnectionError):
            return
        if os.environ.get("XSL_DEBUG"):
            traceback.print_exc()
        self.say(f"internal error on a request from {client_address[0]}: "
                 f"{kind.__name__}: {error} (set XSL_DEBUG=1 for the traceback)")

    def say(self, message: str) -> None:
        print(f"experiment: {message}", file=self.log, flush=True)


class ExperimentHandler(BaseHTTPRequestHandler):
    server: ExperimentServer
    server_version = "xsl-render-experiment"

    def setup(self) -> None:
        self.timeout = self.server.request_timeout   # StreamRequestHandler sets it on the socket
        super().setup()

    def log_message(self, format, *args) -> None:   # noqa: A002 - http.server's API
        """Quiet: the server reports registrations and answers itself."""

    # --- responses -------------------------------------------------------------------
    def _send(self, status: int, body: bytes, mime: str, cache: bool = False) -> None:
        self.send_response(status)
        self.send_header("Content-Type", mime)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "private, max-age=3600" if cache else "no-store")
        self.send_header("X-Content-Type-Options", "nosniff")
        self.end_headers()
        if self.command != "HEAD":
            self.wfile.write(body)

    def _json(self, status: int, data: dict) -> None:
        self._send(status, json.dumps(data).encode("utf-8"), "application/json")

    def _error(self, status: int, message: str) -> None:
        self._json(status, {"error": message})

    def _body(self) -> dict:
        try:
            length = int(self.headers.get("Content-Length", "0"))
        except ValueError:
            raise InputError("bad Content-Length") from None
        if length <= 0 or length > MAX_BODY_BYTES:
            raise InputError(f"the request body must be 1..{MAX_BODY_BYTES} bytes of JSON")
        try:
            raw = self.rfile.read(length)
        except TimeoutError:
            raise InputError("the request body did not arrive in time") from None
        if len(raw) < length:
            raise InputError("the request body is shorter than its Content-Length")
        return parse_body(raw)

    # --- routes ----------------------------------------------------------------------
    def do_HEAD(self) -> None:  # noqa: N802 - http.server's API
        self.do_GET()

    def do_GET(self) -> None:  # noqa: N802
        path = urlsplit(self.path).path
        if path in self.server.page_bytes:
            body, mime = self.server.page_bytes[path]
            return self._send(HTTPStatus.OK, body, mime)
        if path in self.server.stimulus_bytes:
            return self._send(HTTPStatus.OK, self.server.stimulus_bytes[path], "image/png",
                              cache=True)
        if path == "/api/config":
            return self._json(HTTPStatus.OK, self.server.config())
        if path.startswith("/api/participants/"):
            participant_id = unquote(path[len("/api/participants/"):])
            try:
                plan = self.server.store.plan(participant_id)
            except NotFound as error:
                return self._error(HTTPStatus.NOT_FOUND, str(error))
            return self._json(HTTPStatus.OK, self.server.plan_json(plan))
        return self._error(HTTPStatus.NOT_FOUND, "not found")

    def do_POST(self) -> None:  # noqa: N802
        path = urlsplit(self.path).path
        try:
            if path == "/api/participants":
                return self._register(self._body())
            if path == "/api/answers":
                return self._answer(self._body())
        except InputError as error:
            return self._error(HTTPStatus.BAD_REQUEST, str(error))
        except Conflict as error:
            return self._error(HTTPStatus.CONFLICT, str(error))
        except NotFound as error:
            return self._error(HTTPStatus.NOT_FOUND, str(error))
        return self._error(HTTPStatus.NOT_FOUND, "not found")

    def _register(self, body: dict) -> None:
        server = self.server
        plan = server.store.register(
            participant_id=body.get("participant_id"), age_range=body.get("age_range"),
            vision_corrected=body.get("vision_corrected"),
            display={**(body.get("display") if isinstance(body.get("display"), dict) else {}),
                     "user_agent": self.headers.get("User-Agent", "")},
            scenes=sorted(server.pairs), allowed_conditions=server.conditions, rng=server.rng)
        server.say(f"participant {plan.participant_id} registered: {plan.condition}")
        self._json(HTTPStatus.CREATED, server.plan_json(plan))

    def _answer(self, body: dict) -> None:
        participant_id, scene = body.get("participant_id"), body.get("scene")
        if not isinstance(participant_id, str) or not isinstance(scene, str):
            raise InputError("participant_id and scene are needed")
        self.server.store.record_answer(participant_id, scene, body.get("choice"),
                                        body.get("events"), bool(body.get("page_hidden")))
        plan = self.server.store.plan(participant_id)
        left = len(plan.trials) - len(plan.answered)
        self.server.say(f"participant {participant_id} answered {scene} ({left} trials left)")
        self._json(HTTPStatus.CREATED, {"stored": True, "trials_left": left})


def parse_body(raw: bytes) -> dict:
    """A request body as a JSON object of plain values, or InputError (the answer is 400):
    not UTF-8, not JSON, nested deeper than the page ever sends, NaN or Infinity, integers
    longer than a time stamp, numbers past a float's range."""
    def refuse(text):
        raise ValueError(f"{text} is not a number a request may hold")

    def integer(text: str) -> int:
        if len(text.lstrip("-")) > MAX_INT_DIGITS:
            refuse("an integer of more than 18 digits")
        return int(text)

    def number(text: str) -> float:
        value = float(text)
        if value in (float("inf"), float("-inf")):
            refuse(text)
        return value

    try:
        data = json.loads(raw, parse_constant=refuse, parse_int=integer, parse_float=number)
    except (ValueError, RecursionError):        # UnicodeDecodeError and JSONDecodeError too
        raise InputError("the request body is not JSON a request may hold") from None
    if not isinstance(data, dict):
        raise InputError("the request body must be a JSON object")
    if _depth(data) > MAX_JSON_DEPTH:
        raise InputError("the request body is nested too deeply")
    return data


def _depth(value) -> int:
    """How deeply lists and objects nest in ``value`` (counted without recursion)."""
    deepest, stack = 0, [(value, 1)]
    while stack:
        item, depth = stack.pop()
        if isinstance(item, dict):
            item = list(item.values())
        if isinstance(item, list):
            deepest = max(deepest, depth)
            stack.extend((child, depth + 1) for child in item)
    return deepest


def start_server(pairs: list[StimulusPair], db_path: Path, host: str, port: int,
                 conditions: tuple[str, ...], log=None,
                 request_timeout: float = REQUEST_TIMEOUT_S) -> ExperimentServer:
    """Bind the server, then open the store (so a port in use leaves no database behind).

    Raises InputError when the port cannot be had or the database cannot be used.
    """
    server = ExperimentServer((host, port), pairs, conditions, log, request_timeout)
    try:
        server.store = ExperimentStore(db_path)
    except BaseException:
        server.server_close()
        raise
    try:
        server.store.sync_stimuli(pairs)
    except BaseException:
        server.store.close()
        server.server_close()
        raise
    return server
