"""The closed loop wired to the drivers' simulators in subprocesses (spray-out → ma3 spectrophotometer).

Each spray-out panel (the in-process physical model, SYNTHETIC) is handed to the simulators as a
design file, since that is what they take: the panel is the face/flop/travel fit of its 15/45/110 Lab.
The ma3 spectrophotometer simulator is started on it as a real subprocess per panel and the driver's
spectra go through the model's spectra → Lab, the path a lab bench takes; the gloss meter simulator is
read once through its own subprocess (each start costs ~2 s here, so the loop's gloss comes from the
spray-out model). The design itself is a face/flop/travel design, as the designer produces.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from station import drivers
from station.drivers import simproc
from station.formulate.closed_loop import closed_loop
from station.formulate.colorants import predict_lab
from station.formulate.demo import generate_recipes
from station.formulate.sprayout import SprayOutModel
from station.model import AspecularMeasurements, fit_fftg
from station.model.design_io import save_design
from station.model.difference import delta_e
from station.model.spectra import reflectance_to_lab

A3 = (15.0, 45.0, 110.0)


class SimulatedBench:
    """measure(recipe): spray a panel, hand it to the simulators as a design file, read the drivers."""

    def __init__(self, spray: SprayOutModel, folder: Path) -> None:
        self.spray = spray
        self.folder = folder
        self.panels = 0

    def measure(self, recipe: dict[str, float]) -> AspecularMeasurements:
        c = self.spray.model_db.check(self.spray.model_db.vector(recipe))
        lab = self.spray.true_lab(c)
        panel = fit_fftg(AspecularMeasurements(A3, lab, 88.0)).design
        self.panels += 1
        path = save_design(panel, self.folder / f"panel-{self.panels}.json")
        with simproc.spawn_simulator("ma3", design_file=path, extra_args=["--measure-time", "0.02"]) as sim:
            with drivers.open_instrument(sim.address, timeout_s=2.0) as inst:
                reading = inst.measure()
        angles, spectra = reading.block(45)
        gloss = float(self.spray.measure(recipe).gloss_gu or 0.0)
        return AspecularMeasurements(tuple(float(a) for a in angles), reflectance_to_lab(spectra), gloss)


@pytest.mark.slow
def test_closed_loop_through_simulator_subprocesses(tmp_path: Path) -> None:
    # a red metallic (L*15 77): the simulators' design-file panels take only colours inside the
    # object-colour solid (reflectance <= 1), so not one of the generator's bright silvers
    _, conc = generate_recipes(0, 1, 0, seed=100)
    assert predict_lab(conc[0], A3)[0, 0] < 100.0
    design = fit_fftg(AspecularMeasurements(A3, predict_lab(conc[0], A3), 88.0)).design
    save_design(design, tmp_path / "design.json")
    with simproc.spawn_simulator(
        "gloss", design_file=tmp_path / "design.json", extra_args=["--measure-time", "0.02"]
    ) as sim:
        with drivers.open_instrument(sim.address, timeout_s=2.0) as inst:
            assert abs(inst.measure().gloss_gu[60] - 88.0) < 1.0  # the gloss meter reads the design's gloss
    design_lab = design.lab_at(np.array(A3))
    bench = SimulatedBench(SprayOutModel(seed=3), tmp_path)
    job = closed_loop(design_lab, bench.measure, starts=[("near", conc[0] * 0.9)])
    assert job.status == "converged", job.message
    assert job.corrections <= 3
    last = job.steps[-1]
    assert np.allclose(last.de_per_angle, delta_e(design_lab, np.array(last.measured_lab), "cie2000"))
    assert bench.panels == len(job.steps)
