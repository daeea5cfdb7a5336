"""The 3D view with its pickers: environment, shape, exposure, camera reset."""

from __future__ import annotations

from PySide6.QtCore import Qt
from PySide6.QtWidgets import QComboBox, QHBoxLayout, QLabel, QPushButton, QSlider, QVBoxLayout, QWidget

from station.render.shapes import SHAPES
from ui.models.view import ENVIRONMENTS, ViewModel, ViewSettings
from ui.widgets.render_view import make_render_view

EXPOSURE_STEPS_PER_EV = 10


class ViewPanel(QWidget):
    """Pickers above the render view; they write :class:`ViewModel` settings."""

    def __init__(self, model: ViewModel, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        s = model.settings
        self.environment = QComboBox()
        self.environment.addItems(list(ENVIRONMENTS))
        self.environment.setCurrentText(s.environment)
        self.shape = QComboBox()
        self.shape.addItems(list(SHAPES))
        self.shape.setCurrentText(s.shape)
        self.exposure = QSlider(Qt.Orientation.Horizontal)
        self.exposure.setRange(-4 * EXPOSURE_STEPS_PER_EV, 4 * EXPOSURE_STEPS_PER_EV)
        self.exposure.setValue(round(s.exposure_ev * EXPOSURE_STEPS_PER_EV))
        self.exposure_label = QLabel()
        reset = QPushButton("Reset camera")
        bar = QHBoxLayout()
        for w in (
            QLabel("environment"),
            self.environment,
            QLabel("shape"),
            self.shape,
            QLabel("exposure"),
            self.exposure,
            self.exposure_label,
            reset,
        ):
            bar.addWidget(w)
        self.view = make_render_view(model)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(2, 2, 2, 2)
        lay.addLayout(bar)
        lay.addWidget(self.view, 1)
        self.environment.currentTextChanged.connect(lambda t: self.model.update(environment=t))
        self.shape.currentTextChanged.connect(
            lambda t: self.model.update(shape=t, yaw_deg=0.0, pitch_deg=0.0, zoom=1.0)
        )
        self.exposure.valueChanged.connect(lambda v: self.model.update(exposure_ev=v / EXPOSURE_STEPS_PER_EV))
        reset.clicked.connect(lambda: self.model.update(yaw_deg=0.0, pitch_deg=0.0, zoom=1.0))
        model.events.settings.connect(self._on_settings)
        self._on_settings(s)

    def _on_settings(self, s: ViewSettings) -> None:
        self.exposure_label.setText(f"{s.exposure_ev:+.1f} EV")

    def closeEvent(self, event) -> None:
        self.model.events.settings.disconnect(self._on_settings)
        self.view.close()
        super().closeEvent(event)
