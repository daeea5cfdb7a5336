"""The domain's limits and names load without colour-science, SciPy or Matplotlib (which take a second or
more), so a command line that only needs them answers at once; the model's fit loads on first use, and
it too needs none of them (its Lab and sRGB formulae are NumPy): colour-science loads with the first
computation that uses it, such as a CIE 1976 colour difference."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from tests.processes import run

REPO = Path(__file__).resolve().parents[2]
HEAVY = ("colour", "scipy", "matplotlib")

_PROBE = """
import json, sys
import station.model.domain, station.model.angles, station.model.errors
before = sorted(m for m in {heavy} if m in sys.modules)

def delta_e_loads():
    from station.model.difference import delta_e
    delta_e([[50.0, 0.0, 0.0]], [[51.0, 0.0, 0.0]], "cie76")
    return sorted(m for m in {heavy} if m in sys.modules)
from station.model import fit_fftg, FaceFlopTravelGloss
print(json.dumps({{"before": before, "after": sorted(m for m in {heavy} if m in sys.modules),
                  "fit": fit_fftg.__module__, "design": FaceFlopTravelGloss.__module__,
                  "modules": sorted(m for m in sys.modules if m.startswith("station.model.")),
                  "computed": delta_e_loads()}}))
"""


def test_domain_is_cheap_and_the_fit_loads_on_first_use() -> None:
    done = run([sys.executable, "-c", _PROBE.format(heavy=HEAVY)], cwd=REPO, timeout=120)
    assert done.returncode == 0, done.stderr
    out = json.loads(done.stdout)
    assert out["before"] == []
    assert out["after"] == []  # the model itself is cheap ...
    assert {"station.model.fit", "station.model.representations"} <= set(out["modules"])  # ... and loaded
    assert "colour" in out["computed"]  # the probe sees colour-science once a computation needs it
    assert out["fit"] == "station.model.fit" and out["design"] == "station.model.representations"


def test_an_unknown_name_is_still_an_attribute_error() -> None:
    import station.model

    try:
        station.model.no_such_name  # noqa: B018 - the attribute access is the test
    except AttributeError as exc:
        assert "no_such_name" in str(exc)
    else:
        raise AssertionError("station.model invented an attribute")
