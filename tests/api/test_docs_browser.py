"""The API documentation pages work in a real browser without the internet: headless Chromium opens
``/docs`` (Swagger UI 5, which reads the OpenAPI 3.1 schema FastAPI writes) and ``/redoc`` of a real
``station serve`` and finds every tag of the schema drawn, and no "Unable to render this definition".

Chromium comes from the system (scripts/setup.sh installs it); without it the test skips, and fails
under ``CI=true``."""

from __future__ import annotations

import re
import shutil
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest
from PIL import Image

from tests.processes import run
from tests.serve_process import ServeProcess, ServeStartError, serving
from tests.services import service_missing

REPO = Path(__file__).resolve().parents[2]


def _chromium() -> str:
    for name in ("chromium", "chromium-browser", "google-chrome"):
        found = shutil.which(name)
        if found:
            return found
    service_missing("no Chromium on PATH for the docs pages' test (scripts/setup.sh installs it)")


@pytest.fixture(scope="module")
def service(tmp_path_factory: pytest.TempPathFactory) -> Iterator[ServeProcess]:
    import os

    env = dict(os.environ, CACAD_PUBLIC_DOCS="true")
    try:
        with serving(
            tmp_path_factory.mktemp("docs"), "--no-demo-library", "--simulators", "", cwd=REPO, env=env
        ) as svc:
            yield svc
    except ServeStartError as exc:
        pytest.fail(str(exc))


def _browse(browser: str, url: str, out: Path, *mode: str) -> str:
    """Load *url* in headless Chromium (15 s of virtual time for the scripts) with *mode* flags."""
    profile = out / "profile"
    argv = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
            f"--user-data-dir={profile}", "--window-size=1280,1000", "--virtual-time-budget=15000",
            *mode, url]  # fmt: skip
    done = run(argv, timeout=120, cwd=out)
    assert done.returncode == 0, done.stderr[-2000:]
    return done.stdout


def test_swagger_ui_draws_every_tag_of_the_3_1_schema(service: ServeProcess, tmp_path: Path) -> None:
    browser = _chromium()
    schema = httpx.get(f"{service.base}/openapi.json", timeout=30).json()
    assert schema["openapi"].startswith("3.1")
    dom = _browse(browser, f"{service.base}/", tmp_path, "--dump-dom")  # the front door leads to /docs
    assert "Unable to render this definition" not in dom
    drawn_tags = set(re.findall(r'data-tag="([^"]+)"', dom))
    used = {t for ops in schema["paths"].values() for op in ops.values() for t in op.get("tags", ())}
    assert drawn_tags == used == {t["name"] for t in schema["tags"]}  # each tag drawn and described
    paths = set(re.findall(r'class="opblock-summary-path" data-path="([^"]+)"', dom))
    assert "/api/v1/measurements" in paths and len(paths) >= len(schema["paths"]) // 2
    shot = tmp_path / "docs.png"
    _browse(browser, f"{service.base}/docs", tmp_path, f"--screenshot={shot}")
    with Image.open(shot) as img:
        colours = img.convert("RGB").resize((64, 50)).getcolors(64 * 50)
    assert colours is not None and len(colours) > 20  # drawn, not a blank page


def test_redoc_draws_the_schema(service: ServeProcess, tmp_path: Path) -> None:
    dom = _browse(_chromium(), f"{service.base}/redoc", tmp_path, "--dump-dom")
    assert "CACAD Station" in dom and "api/v1/measurements" in dom
    assert "Something went wrong" not in dom
