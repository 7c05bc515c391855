"""experiment-serve without a browser: what it serves, what it refuses, how it fails."""
from __future__ import annotations

import http.client
import json
import signal
import socket
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest

from xsl_render.core.imageio import write_png
from xsl_render.core.psychophysics.stimuli import scan_stimuli
from xsl_render.operators.experiment_web.server import start_server

SECRET = "TOP-SECRET-NOT-A-STIMULUS"


def make_stimuli(folder: Path, scenes=("alpha", "beta"), size=(48, 64)) -> Path:
    rng = np.random.default_rng(3)
    folder.mkdir(parents=True, exist_ok=True)
    for scene in scenes:
        gold = rng.random((*size, 3)).astype(np.float32)
        write_png(folder / f"{scene}.gold.png", gold)
        write_png(folder / f"{scene}.test.png", np.clip(gold + 0.3 * rng.standard_normal(gold.shape), 0, 1))
    return folder


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    tmp_path = tmp_path_factory.mktemp("served")
    (tmp_path / "secret.txt").write_text(SECRET)
    stimuli = make_stimuli(tmp_path / "stimuli")
    (stimuli / "notes.txt").write_text(SECRET)
    srv = start_server(scan_stimuli(stimuli), stimuli / "experiment.sqlite", "127.0.0.1", 0,
                       ("no-reference", "reference"), log=open(tmp_path / "server.log", "w"))
    thread = threading.Thread(target=srv.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True)
    thread.start()
    yield srv
    srv.shutdown()
    srv.server_close()
    srv.store.close()


def request(srv, method, path, body=None):
    connection = http.client.HTTPConnection(*srv.server_address[:2], timeout=10)
    try:
        # skip_host etc. are not needed; putrequest sends the path exactly as given.
        connection.putrequest(method, path, skip_accept_encoding=True)
        data = json.dumps(body).encode() if body is not None else b""
        connection.putheader("Content-Length", str(len(data)))
        connection.endheaders(data)
        response = connection.getresponse()
        return response.status, response.read()
    finally:
        connection.close()


@pytest.mark.parametrize("path", [
    "/../secret.txt", "/stimuli/../../secret.txt", "/stimuli/..%2F..%2Fsecret.txt",
    "/%2e%2e/%2e%2e/secret.txt", "/stimuli/alpha.gold.png", "/alpha.gold.png",
    "/stimuli/notes.txt", "/notes.txt", "/experiment.sqlite", "/stimuli/experiment.sqlite",
    "/experiment.js/../../secret.txt", "//etc/passwd", "/static/../../../../etc/passwd",
    "/api/participants/..%2F..%2Fsecret.txt", "/index.html", "/experiment_page/index.html",
])
def test_nothing_outside_the_stimuli_tables_is_served(server, path):
    status, body = request(server, "GET", path)
    assert status == 404
    assert SECRET.encode() not in body and b"root:" not in body and b"SQLite" not in body


def test_page_stimuli_and_answers_round_trip(server):
    assert request(server, "GET", "/")[0] == 200
    assert request(server, "GET", "/experiment.js")[0] == 200
    status, body = request(server, "POST", "/api/participants",
                           {"participant_id": "p1", "age_range": "18-24", "vision_corrected": True})
    assert status == 201
    plan = json.loads(body)
    assert plan["condition"] == "no-reference" and len(plan["trials"]) == 2
    urls = [url for trial in plan["trials"] for url in trial["images"].values()]
    for url in urls:             # the URLs do not tell which image is the gold standard
        assert "gold" not in url and "test" not in url
        status, png = request(server, "GET", url)
        assert status == 200 and png.startswith(b"\x89PNG")
    again = request(server, "POST", "/api/participants",
                    {"participant_id": "p1", "age_range": "18-24", "vision_corrected": True})
    assert again[0] == 409
    events = {"first_on": 0, "first_off": 4000, "second_on": 6000, "second_off": 10000}
    answer = {"participant_id": "p1", "scene": plan["trials"][0]["scene"], "choice": "first",
              "events": events}
    assert request(server, "POST", "/api/answers", answer)[0] == 201
    assert request(server, "POST", "/api/answers", answer)[0] == 409
    assert request(server, "POST", "/api/answers", {**answer, "choice": "left"})[0] in (400, 409)
    assert request(server, "POST", "/api/answers", {**answer, "participant_id": "ghost"})[0] == 404
    status, body = request(server, "GET", "/api/participants/p1")
    assert status == 200 and sum(t["answered"] for t in json.loads(body)["trials"]) == 1
    # A second participant gets the other condition and the reference image.
    status, body = request(server, "POST", "/api/participants",
                           {"participant_id": "p2", "age_range": "65+", "vision_corrected": False})
    assert json.loads(body)["condition"] == "reference"
    assert set(json.loads(body)["trials"][0]["images"]) == {"left", "right", "reference"}


@pytest.mark.parametrize("body", [b"not json", b"[1, 2]", b""])
def test_malformed_requests_get_400(server, body):
    connection = http.client.HTTPConnection(*server.server_address[:2], timeout=10)
    connection.request("POST", "/api/participants", body=body,
                       headers={"Content-Type": "application/json"})
    assert connection.getresponse().status == 400
    connection.close()


def test_port_in_use_is_exit_2(tmp_path, cli):
    stimuli = make_stimuli(tmp_path / "stimuli")
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        result = cli("experiment-serve", stimuli, "--port", port, timeout=60)
    assert result.returncode == 2
    assert result.stderr.strip().count("\n") == 0 and "in use" in result.stderr
    assert "Traceback" not in result.stderr
    assert not (stimuli / "experiment.sqlite").exists()


@pytest.mark.parametrize("problem", ["unmatched", "sizes", "missing"])
def test_bad_stimuli_folder_is_exit_2(tmp_path, cli, problem):
    stimuli = make_stimuli(tmp_path / "stimuli", scenes=("alpha",))
    if problem == "unmatched":
        (stimuli / "alpha.test.png").rename(stimuli / "beta.test.png")
    elif problem == "sizes":
        write_png(stimuli / "alpha.test.png", np.zeros((10, 10, 3), np.float32))
    else:
        stimuli = tmp_path / "nowhere"
    result = cli("experiment-serve", stimuli, "--port", "0", timeout=60)
    assert result.returncode == 2
    assert result.stderr.startswith("xsl-render: error:") and result.stderr.count("\n") == 1


def _post_raw(srv, path: str, body: bytes, length: int | None = None) -> int:
    connection = http.client.HTTPConnection(*srv.server_address[:2], timeout=10)
    try:
        connection.putrequest("POST", path)
        connection.putheader("Content-Type", "application/json")
        connection.putheader("Content-Length", str(len(body) if length is None else length))
        connection.endheaders(body)
        return connection.getresponse().status
    finally:
        connection.close()


@pytest.mark.parametrize("body", [
    b"[" * 30000 + b"]" * 30000,                                         # deeper than json can parse
    b'{"participant_id": "p9", "age_range": "18-24", "vision_corrected": true, "display": '
    + b'{"a": ' * 20 + b"1" + b"}" * 20 + b"}",                          # nested deeper than the page sends
    b'{"participant_id": "p9", "age_range": "18-24", "vision_corrected": NaN}',
    b'{"participant_id": "p9", "age_range": "18-24", "vision_corrected": true, "display": {"w": 1e400}}',
    b'{"participant_id": "p9", "n": ' + b"9" * 5000 + b"}",              # past int's text limit
    b"\xff\xfe not utf-8",
], ids=["nested-array", "nested-object", "nan", "float-overflow", "long-int", "bytes"])
def test_unparsable_bodies_get_400_and_the_server_goes_on(server, body):
    """Issue 15, point 10: these used to raise inside the handler (no answer at all)."""
    assert _post_raw(server, "/api/participants", body) == 400
    assert request(server, "GET", "/")[0] == 200


def test_time_stamps_past_a_float_get_400(server):
    status, body = request(server, "POST", "/api/participants",
                           {"participant_id": "big1", "age_range": "18-24", "vision_corrected": True})
    assert status == 201
    scene = json.loads(body)["trials"][0]["scene"]
    events = {"first_on": 0, "first_off": 4000, "second_on": 6000, "second_off": 10 ** 18}
    raw = json.dumps({"participant_id": "big1", "scene": scene, "choice": "first", "events": events})
    assert _post_raw(server, "/api/answers", raw.replace(str(10 ** 18), "1" + "0" * 400).encode()) == 400
    events.update(second_off=10000, answer_at=10 ** 17)     # 18 digits: a number, if an odd one
    status, _ = request(server, "POST", "/api/answers",
                        {"participant_id": "big1", "scene": scene, "choice": "first", "events": events})
    assert status == 201


@pytest.mark.parametrize("participant_id", ["p1\n", "p1\r\n", "\np1", "p 1", "-p1", "x" * 65])
def test_participant_ids_are_checked_to_their_last_character(server, participant_id):
    """Issue 15, point 10: ``$`` matched before a trailing newline; ids are anchored at \\Z."""
    status, _ = request(server, "POST", "/api/participants",
                        {"participant_id": participant_id, "age_range": "18-24", "vision_corrected": True})
    assert status == 400


def test_a_body_shorter_than_its_length_gets_400_after_the_timeout(tmp_path):
    stimuli = make_stimuli(tmp_path / "stimuli")
    srv = start_server(scan_stimuli(stimuli), tmp_path / "a.sqlite", "127.0.0.1", 0, ("reference",),
                       log=open(tmp_path / "server.log", "w"), request_timeout=0.5)
    thread = threading.Thread(target=srv.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True)
    thread.start()
    try:
        assert _post_raw(srv, "/api/participants", b'{"participant_id": ', length=500) == 400
        with socket.create_connection(srv.server_address[:2], timeout=10) as silent:
            silent.sendall(b"POST /api/participants HTTP/1.1\r\n")        # and nothing more
            assert silent.recv(100) == b""          # the server hangs up instead of waiting forever
        assert request(srv, "GET", "/")[0] == 200
    finally:
        srv.shutdown()
        srv.server_close()
        srv.store.close()


@pytest.mark.parametrize("signum, code", [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_a_server_started_with_sigint_ignored_still_stops(tmp_path, signum, code):
    """Issue 23, point 3: a background job of a shell script starts with SIGINT ignored; the
    server used to ignore SIGTERM and SIGINT then (``interrupt_main`` does nothing without
    Python's handler) and, stopped, exited 0. It installs its own and exits 130/143."""
    stimuli = make_stimuli(tmp_path / "stimuli", scenes=("alpha",), size=(4, 4))
    exe = Path(sys.executable).with_name("xsl-render")
    process = subprocess.Popen([str(exe), "experiment-serve", str(stimuli), "--port", "0"],
                               preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_IGN),
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        lines = []
        while not any("http://" in line for line in lines):
            lines.append(process.stdout.readline())
            assert lines[-1], f"experiment-serve did not start: {process.stderr.read()}"
        process.send_signal(signum)
        out, err = process.communicate(timeout=20)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    assert process.returncode == code, err
    assert "stopped; every answer given is in the database" in out and "Traceback" not in err
