"""An uploaded HDR environment over real HTTP: the documented 4 MiB file cap holds although the JSON body
is larger than the service's general 1 MiB cap (base64 adds a third); beyond it, 413. The multipart route
(``/styling/render/upload``, the file as a part) takes venice_sunset (1.40 MB, 1.86 MB as base64) and refuses a 5 MiB one with a 413
naming ``environment_hdr``, and a file that is no HDR image with a 422 naming it."""

from __future__ import annotations

import base64
import io
import json
import signal
from collections.abc import Iterator
from pathlib import Path

import httpx
import numpy as np
import pytest
from PIL import Image

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


def _hdr_of_size(path: Path, width: int, height: int) -> bytes:
    """An uncompressed Radiance .hdr of width × height pixels (4 bytes each plus the header)."""
    from station.render.hdr_io import write_hdr

    rng = np.random.default_rng(7)
    write_hdr(path, rng.uniform(0.1, 2.0, (height, width, 3)).astype(np.float32), rle=False)
    return path.read_bytes()


def _multipart(base: str, token: str, data: bytes, request: dict | None = None) -> httpx.Response:
    files = {"environment_hdr": ("map.hdr", data, "application/octet-stream")}
    form = {} if request is None else {"request": json.dumps(request)}
    return httpx.post(
        f"{base}/api/v1/styling/render/upload",
        files=files,
        data=form,
        headers={"Authorization": f"Bearer {token}"},
        timeout=120,
    )


def _field(r: httpx.Response) -> list:
    return r.json()["detail"][0]["loc"]


def test_multipart_upload_takes_the_documented_4_mib(service, shared_dir: Path, tmp_path: Path) -> None:
    base, token = service
    hdr = shared_dir / "data" / "hdri" / "venice_sunset_1k.hdr"
    if not hdr.is_file():
        pytest.skip("no venice_sunset_1k.hdr in ../shared/data/hdri")
    data = hdr.read_bytes()
    # 1.40 MB, 1.86 MB as base64: over the general 1 MiB cap either way
    assert GENERAL_CAP < len(data) <= MAX_UPLOAD_BYTES and len(base64.b64encode(data)) > 1_850_000
    r = _multipart(base, token, data, {"size": 32, "shape": "sphere"})
    assert r.status_code == 200, r.text[:300]
    assert r.headers["content-type"] == "image/png"
    img = Image.open(io.BytesIO(r.content))
    assert img.size == (32, 32)
    # the same picture as the base64 route's (one renderer, one environment)
    b64 = httpx.post(
        f"{base}/api/v1/styling/render",
        json={"environment_hdr": base64.b64encode(data).decode(), "size": 32, "shape": "sphere"},
        headers={"Authorization": f"Bearer {token}"},
        timeout=120,
    )
    assert b64.status_code == 200 and np.array_equal(
        np.asarray(img), np.asarray(Image.open(io.BytesIO(b64.content)))
    )


def test_multipart_upload_refusals_name_the_field(service, tmp_path: Path) -> None:
    base, token = service
    # 5 MiB of pixels (1280 x 1024, 4 bytes each) plus the header: over the 4 MiB cap → 413 naming the file
    big = _hdr_of_size(tmp_path / "big.hdr", 1280, 1024)
    assert len(big) > 5 * 1_048_576
    r = _multipart(base, token, big)
    assert r.status_code == 413 and _field(r) == ["body", "environment_hdr"], r.text[:300]
    # just over 4 MiB: the body fits the route's cap (file + 64 KiB), the file part does not
    over = _hdr_of_size(tmp_path / "over.hdr", 1025, 1024)
    assert MAX_UPLOAD_BYTES < len(over) < MAX_UPLOAD_BYTES + 16_384
    r = _multipart(base, token, over)
    assert r.status_code == 413 and _field(r) == ["body", "environment_hdr"], r.text[:300]
    # not an HDR image: 422 naming the file part
    r = _multipart(base, token, b"\x89PNG\r\n\x1a\n" + b"\x00" * 4096)
    assert r.status_code == 422 and _field(r) == ["body", "environment_hdr"], r.text[:300]
    # a bad render option: 422 naming it inside the request part
    small = _hdr_of_size(tmp_path / "small.hdr", 64, 32)
    r = _multipart(base, token, small, {"size": 0})
    assert r.status_code == 422 and _field(r)[:2] == ["request", "size"], r.text[:300]
    # no file part: 422 naming it
    r = httpx.post(
        f"{base}/api/v1/styling/render/upload",
        files={"request": ("r.json", b"{}", "application/json")},
        headers={"Authorization": f"Bearer {token}"},
        timeout=60,
    )
    assert r.status_code == 422 and _field(r) == ["body", "environment_hdr"], r.text[:300]
