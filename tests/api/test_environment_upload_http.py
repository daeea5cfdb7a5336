"""An uploaded HDR environment over real HTTP: the documented 4 MiB file cap holds although the JSON body
is larger than the service's general 1 MiB cap (base64 adds a third); beyond it, 413."""

from __future__ import annotations

import base64
import signal
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest

from station.api.schemas.environment import ENVIRONMENT_BODY_BYTES
from station.api.settings import BOOTSTRAP_TOKEN_FILE
from station.render.scene_image import MAX_UPLOAD_BYTES
from tests.serve_process import ServeProcess, ServeStartError, serve_env, upgrade_data_dir

GENERAL_CAP = 1_048_576


@pytest.fixture(scope="module")
def service(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[str, str]]:
    data_dir = tmp_path_factory.mktemp("serve") / "data"
    env = serve_env(CACAD_MAX_BODY_BYTES=str(GENERAL_CAP))
    upgrade_data_dir(data_dir, env)
    svc = ServeProcess(data_dir, ("--simulators", "", "--no-demo-library"), env=env, start_timeout_s=60)
    try:
        svc.start()
    except ServeStartError as exc:
        pytest.fail(str(exc))
    try:
        yield svc.base, (data_dir / BOOTSTRAP_TOKEN_FILE).read_text().strip()
    finally:
        svc.stop(signal.SIGTERM)


def test_venice_sunset_upload_is_served(service, shared_dir: Path) -> None:
    base, token = service
    hdr = shared_dir / "data" / "hdri" / "venice_sunset_1k.hdr"
    if not hdr.is_file():
        pytest.skip("no venice_sunset_1k.hdr in ../shared/data/hdri")
    data = hdr.read_bytes()
    text = base64.b64encode(data).decode()
    assert len(text) > GENERAL_CAP and len(data) <= MAX_UPLOAD_BYTES  # the case the general cap refused
    auth = {"Authorization": f"Bearer {token}"}
    r = httpx.post(
        f"{base}/api/v1/styling/render",
        json={"environment_hdr": text, "size": 32},
        headers=auth,
        timeout=120,
    )
    assert r.status_code == 200, r.text[:300]
    assert r.headers["content-type"] == "image/png"
    # Over the route's own cap: 413 before the body is read; the general cap still holds elsewhere.
    big = {"environment_hdr": "A" * ENVIRONMENT_BODY_BYTES}
    r = httpx.post(f"{base}/api/v1/styling/render", json=big, headers=auth, timeout=60)
    assert r.status_code == 413
    r = httpx.post(
        f"{base}/api/v1/styling/eyedrop", content=b"x" * (GENERAL_CAP + 1), headers=auth, timeout=60
    )
    assert r.status_code == 413
