"""What a new user's trial of the test station's routes found, over real HTTP on the
simulated analyzer: a setup is a stored setup's name (never a server path), practice
hits are checked against the analyzer before any hit, the 409s say what to do, a stale
setup version says to load it again, a body that is not JSON says so, a setup's older
version is served, a negative hit index is refused, and the snapshot names the setup
the next capture will use."""

from __future__ import annotations

import pytest

from daq.store.setups import SetupStore
from tests.service.service_helpers import serving, wait_for

pytestmark = pytest.mark.slow

BENCH = {"span_hz": 400.0, "hammer": {"transducer": "hammer-default"}, "accelerometer": {}}


def _idle(served, timeout_s: float = 60.0) -> None:
    wait_for(lambda: served.get("/api/capture").json()["state"] == "idle", timeout_s, "idle")


@pytest.fixture(scope="module")
def refusing(tmp_path_factory):
    """One service for the tests below whose requests are refused, or touch only setups
    of their own names (bench, brand-new, x): none starts a capture or practice hits, so
    each finds the service idle with no hit taken, as a fresh one. A service per test
    cost each of them a start (4-5 s) for a few requests."""
    with serving(tmp_path_factory.mktemp("refusing"), "--sim", "--seed", "1", "--time-scale", "0") as served:
        yield served


def test_a_capture_names_a_stored_setup_never_a_server_file(refusing):
    served = refusing
    refused = "setup: give the name of a stored setup (GET /api/setups)"
    for given in ("/etc/passwd.toml", "/etc/passwd", "../setups/x", "x.toml", "./default", "a/b"):
        for route in ("/api/capture", "/api/capture/practice"):
            answer = served.post(route, {"hits": 1, "setup": given})
            assert answer.status_code == 422, (given, route, answer.text)
            assert answer.json() == {"detail": refused}, (given, route)
    # A stored name that is not there is still told as such (no path in it).
    unknown = served.post("/api/capture", {"hits": 1, "setup": "nope"}).json()["detail"]
    assert unknown.startswith("setup: no setup 'nope'")
    assert str(served.store) not in unknown
    assert served.get("/api/capture").json()["state"] == "idle"


def test_the_services_own_setup_file_from_the_command_line_stays_usable(tmp_path):
    setup_file = tmp_path / "bench-file.toml"
    setup_file.write_text("span_hz = 400.0\n")
    with serving(tmp_path, "--sim", "--seed", "1", "--time-scale", "0", "--setup", str(setup_file)) as served:
        nxt = served.get("/api/capture").json()["next_setup"]
        assert nxt == {"name": "bench-file.toml", "version": 0}  # the file's name, not its folder
        answer = served.post("/api/capture", {"hits": 1, "auto": True})
        assert answer.status_code == 202, answer.text
        _idle(served)
        state = served.get("/api/capture").json()
        assert state["last_outcome"] == "sealed", state
        assert str(tmp_path) not in served.get("/api/capture").text
        # Named over HTTP, even the service's own file is refused: a request names stored setups.
        again = served.post("/api/capture", {"hits": 1, "setup": str(setup_file)})
        assert again.status_code == 422


def test_practice_hits_with_a_setup_the_analyzer_cannot_take_are_refused_before_any_hit(tmp_path):
    store = tmp_path / "store"
    setups = SetupStore(store)
    setups.put("fine", {**BENCH, "lines": 800})
    setups.put("heavy", {**BENCH, "trigger_level_eu": 1000.0})
    with serving(tmp_path, "--sim", "--seed", "1", "--time-scale", "0", store=store) as served:
        fine = served.post("/api/capture/practice", {"setup": "fine", "hits": 2})
        assert fine.status_code == 422, fine.text
        assert fine.json() == {"detail": "lines: the 35660A offers 400 lines only, not 800"}
        heavy = served.post("/api/capture/practice", {"setup": "heavy", "hits": 2})
        assert heavy.status_code == 422, heavy.text
        assert heavy.json()["detail"].startswith("trigger_level_eu: 1000 N is above the hammer's range")
        state = served.get("/api/capture").json()
        assert (state["state"], state["practice"]) == ("idle", None)  # no practice was taken
        # as POST /api/capture answers the same setup
        assert served.post("/api/capture", {"hits": 1, "setup": "fine"}).json() == fine.json()
        # and a setup it can take still practises
        ok = served.post("/api/capture/practice", {"setup": "default", "hits": 1})
        assert ok.status_code == 202, ok.text
        _idle(served)
        assert served.get("/api/capture").json()["practice"]["state"] == "done"


def test_a_start_while_practice_hits_are_taken_says_to_stop_them(tmp_path):
    with serving(tmp_path, "--sim", "--seed", "1") as served:  # real time: practice lasts
        assert served.post("/api/capture/practice", {"hits": 100}).status_code == 202
        for route in ("/api/capture", "/api/capture/practice"):
            busy = served.post(route, {"hits": 1})
            assert busy.status_code == 409, busy.text
            assert busy.json() == {
                "detail": "practice hits are being taken; stop them first (POST /api/capture/stop)"
            }
        assert served.post("/api/capture/stop").status_code == 202
        _idle(served)
        # While a capture runs the 409 names its run and what to do, never "run None".
        run_id = served.post("/api/capture", {"hits": 3}).json()["run_id"]
        busy = served.post("/api/capture", {"hits": 1}).json()["detail"]
        assert "None" not in busy
        assert busy == f"a capture is running (run {run_id}); stop it first (POST /api/capture/stop)"
        assert served.post("/api/capture/abort").status_code == 202
        _idle(served)


def test_a_stale_setup_version_says_to_load_it_again(refusing):
    served = refusing
    with served.client() as c:
        assert c.put("/api/setups/bench", json={"setup": BENCH, "version": 0}).status_code == 200
        assert c.put("/api/setups/bench", json={"setup": BENCH, "version": 1}).status_code == 200
        for given in (5, 1):  # one that never existed, one saved over
            stale = c.put("/api/setups/bench", json={"setup": BENCH, "version": given})
            assert stale.status_code == 409
            assert stale.json() == {
                "detail": f"version {given} is not the current one (2): load the setup again"
            }
        new = c.put("/api/setups/brand-new", json={"setup": BENCH, "version": 3})
        assert new.status_code == 409
        assert new.json() == {
            "detail": "version 3: setup brand-new does not exist yet (version 0 saves it new)"
        }
        taken = c.put("/api/setups/bench", json={"setup": BENCH, "version": 0})
        assert taken.status_code == 409
        assert taken.json()["detail"].startswith("version 0: setup bench exists already (version 2)")
        conflict = served.post("/api/capture", {"hits": 1, "setup": "bench", "setup_version": 1})
        assert conflict.status_code == 409
        assert conflict.json() == {
            "detail": "setup_version: version 1 is not the current one (2): load the setup again"
        }


def test_a_body_that_is_not_a_json_object_says_so(refusing):
    expected = {"detail": "body: must be a JSON object (Content-Type: application/json)"}
    served = refusing
    with served.client() as c:
        form = c.post(
            "/api/capture", content=b"a=b", headers={"Content-Type": "application/x-www-form-urlencoded"}
        )
        assert (form.status_code, form.json()) == (422, expected)
        for body in ([1, 2], "text", 5):
            answer = c.post("/api/capture/decision", json=body)
            assert (answer.status_code, answer.json()) == (422, expected), body
        put = c.put("/api/transducers/h-1", json=[1])
        assert (put.status_code, put.json()) == (422, expected)
        setup = c.put(
            "/api/setups/x", content=b"a=b", headers={"Content-Type": "application/x-www-form-urlencoded"}
        )
        assert (setup.status_code, setup.json()) == (422, expected)
        # The other messages are kept.
        bad_json = c.post("/api/capture", content=b"{", headers={"Content-Type": "application/json"})
        assert bad_json.json() == {"detail": "body: not valid JSON"}
        wrong = c.post("/api/capture", json={"hits": "5"})
        assert wrong.status_code == 422
        assert wrong.json()["detail"].startswith("hits: ")


def test_a_setups_older_version_is_served(refusing):
    served = refusing
    with served.client() as c:
        assert c.put("/api/setups/x", json={"setup": BENCH, "version": 0}).status_code == 200
        second = {**BENCH, "span_hz": 200.0}
        assert c.put("/api/setups/x", json={"setup": second, "version": 1}).status_code == 200
    first = served.get("/api/setups/x", params={"version": 1})
    assert first.status_code == 200, first.text
    assert (first.json()["version"], first.json()["setup"]["span_hz"]) == (1, 400.0)
    assert first.json()["settings"]["span_hz"] == 400.0
    current = served.get("/api/setups/x", params={"version": 2}).json()
    assert (current["version"], current["setup"]["span_hz"]) == (2, 200.0)
    assert served.get("/api/setups/x").json()["version"] == 2
    missing = served.get("/api/setups/x", params={"version": 9})
    assert (missing.status_code, missing.json()) == (404, {"detail": "setup x has no version 9"})
    assert served.get("/api/setups/default", params={"version": 0}).json()["version"] == 0
    none = served.get("/api/setups/default", params={"version": 3})
    assert (none.status_code, none.json()) == (404, {"detail": "setup default has no version 3"})
    bad = served.get("/api/setups/x", params={"version": "-1"})
    assert bad.status_code == 422
    assert bad.json()["detail"].startswith("query.version: ")
    assert served.get("/api/setups/nope", params={"version": 1}).status_code == 404


def test_a_negative_hit_index_is_refused_as_such(refusing):
    served = refusing
    negative = served.get("/api/capture/hits/-1")
    assert negative.status_code == 422
    assert negative.json() == {"detail": "index: must be 0 or more (hits count from 0 in the API)"}
    assert served.get("/api/capture/hits/0").status_code == 404


def test_the_snapshot_names_the_setup_the_next_capture_uses(tmp_path):
    store = tmp_path / "store"
    SetupStore(store).put("bench", BENCH)
    with serving(
        tmp_path, "--sim", "--seed", "1", "--time-scale", "0", "--setup", "bench", store=store
    ) as served:
        idle = served.get("/api/capture").json()
        assert (idle["setup"], idle["next_setup"]) == (None, {"name": "bench", "version": 1})
        with served.client() as c:
            assert c.put("/api/setups/bench", json={"setup": BENCH, "version": 1}).status_code == 200
        assert served.get("/api/capture").json()["next_setup"] == {"name": "bench", "version": 2}
        served.post("/api/capture", {"hits": 1, "auto": True, "setup": "default"})
        _idle(served)
        after = served.get("/api/capture").json()
        assert (after["setup"], after["next_setup"]) == (
            {"name": "default", "version": 0},
            {"name": "bench", "version": 2},
        )
    (tmp_path / "plain").mkdir()
    with serving(tmp_path / "plain", "--sim", "--seed", "1", "--time-scale", "0") as served:
        assert served.get("/api/capture").json()["next_setup"] is None  # the service's own settings
