"""`daq serve` serves regular run files of its store only, and says nothing of its paths.

A symbolic link named as a run (to /etc/passwd-like secrets, to the service's own
token file), a hard link to the token file, a FIFO named as a run: every route of a
run answers 404 at once, the listing leaves them out, nothing of their target is
served. 404 bodies never name the store's folder. A token file far too large to hold
a token is refused with one line. Real `daq serve` processes and sockets.
"""

from __future__ import annotations

import os

import httpx
import pytest

from daq.store import seal
from tests.cli.run_files import make_run
from tests.cli_helpers import assert_one_line_error
from tests.service.hardening_helpers import run_daq_env
from tests.service.service_helpers import service_env, serving

pytestmark = pytest.mark.slow

SOUND = "20261123T101503.123Z-0000aaaa"
#: What each test puts beside the sound run, named as a run: a name of its own, so that
#: nothing the shared service learnt of one test's entry can answer for another's.
LINKED = {
    "a secret file": "20261124T235959.000Z-deadbeef",
    "the token file": "20261124T235958.000Z-deadbee1",
    "a hard link": "20261124T235957.000Z-deadbee2",
    "a FIFO": "20261124T235956.000Z-deadbee3",
}
SECRET = "the secret outside the store"

RUN_ROUTES = (
    "/api/runs/{}",
    "/api/runs/{}/analysis",
    "/api/runs/{}/frf",
    "/api/runs/{}/fits",
    "/api/runs/{}/file",
    "/api/runs/{}/export?format=csv",
    "/api/runs/{}/export?format=uff",
    "/api/runs/{}/report",
)


def _store_with_a_sound_run(tmp_path):
    store = tmp_path / "store"
    seal(make_run(SOUND), store)
    return store


@pytest.fixture(scope="module")
def sound_service(tmp_path_factory):
    """One service on a store of one sound run for the tests below (a service per test
    cost each a start, 4-5 s); each takes away what it put beside the run."""
    root = tmp_path_factory.mktemp("sound")
    store = _store_with_a_sound_run(root)
    with serving(root, "--sim", "--workers", "1", store=store) as served:
        yield served


@pytest.fixture
def served(sound_service):
    """The shared service, its store holding the sound run alone again after the test."""
    yield sound_service
    for name in LINKED.values():
        path = sound_service.store / f"{name}.h5"
        if os.path.lexists(path):
            path.unlink()


def _assert_refused(client: httpx.Client, run_id: str, secrets: list[str], store) -> None:
    for route in RUN_ROUTES:
        for name in (run_id, run_id[:16]):  # the whole id, and a prefix of it
            response = client.get(route.format(name))
            assert response.status_code == 404, (route, name, response.status_code, response.text[:300])
            for secret in secrets:
                assert secret not in response.text, (route, name, response.text[:300])
            assert str(store) not in response.text, (route, name, response.text)
    listing = client.get("/api/runs")
    assert listing.status_code == 200, listing.text
    assert [row["run_id"] for row in listing.json()] == [SOUND], listing.text


@pytest.mark.parametrize("target", ["a secret file", "the token file"])
def test_a_symlink_in_the_store_serves_nothing(served, tmp_path, target):
    store = served.store
    secret = tmp_path / "secret.txt"
    secret.write_text(SECRET + "\n")
    pointed = secret if target == "a secret file" else served.env["DAQ_TOKEN_FILE"]
    os.symlink(pointed, store / f"{LINKED[target]}.h5")
    with served.client(token=False, timeout=15) as anonymous:
        _assert_refused(anonymous, LINKED[target], [SECRET, served.token], store)
        # The sound run is served as before.
        file = anonymous.get(f"/api/runs/{SOUND}/file")
        assert file.status_code == 200, file.text
        assert file.content.startswith(b"\x89HDF"), file.content[:20]


def test_a_hard_link_to_the_token_file_is_not_served(served):
    os.link(served.env["DAQ_TOKEN_FILE"], served.store / f"{LINKED['a hard link']}.h5")
    with served.client(token=False, timeout=15) as anonymous:
        response = anonymous.get(f"/api/runs/{LINKED['a hard link']}/file")
        assert response.status_code == 404, response.text
        assert served.token not in response.text


def test_a_fifo_named_as_a_run_hangs_nothing(served):
    """Opening a FIFO waits for a writer for ever: the listing and every route of the
    run answer at once, and the service stays responsive."""
    os.mkfifo(served.store / f"{LINKED['a FIFO']}.h5")
    with served.client(token=False, timeout=10) as anonymous:
        _assert_refused(anonymous, LINKED["a FIFO"], [], served.store)
        assert anonymous.get("/api/health").status_code == 200


def test_404_bodies_do_not_name_the_store_folder(served):
    root = served.store.parent
    with served.client(token=False, timeout=15) as anonymous:
        for name in ("2099", "20261125", "1"):
            for route in RUN_ROUTES:
                response = anonymous.get(route.format(name))
                assert response.status_code == 404, (route, name, response.text)
                assert str(served.store) not in response.text, (route, name, response.text)
                assert str(root) not in response.text, (route, name, response.text)


def test_a_token_file_too_large_to_hold_a_token_is_refused_with_one_line(tmp_path):
    env = service_env(tmp_path)
    token_file = tmp_path / "token"
    fd = os.open(token_file, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    with os.fdopen(fd, "w") as handle:
        handle.write("ab" * (8 * 2**20))  # 16 MiB of hex digits
    result = run_daq_env(env, "serve", "--show-token", timeout_s=30)
    assert_one_line_error(result, "token file", "too large")
    assert len(result.stdout) < 100, len(result.stdout)
