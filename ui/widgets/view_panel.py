"""The 3D view with its pickers: environment (built-in or an .hdr/.exr file), shape, exposure, camera reset."""

from __future__ import annotations

from pathlib import Path

from PySide6.QtCore import Qt
from PySide6.QtWidgets import (
    QCheckBox,
    QComboBox,
    QDoubleSpinBox,
    QFileDialog,
    QHBoxLayout,
    QLabel,
    QPushButton,
    QSlider,
    QVBoxLayout,
    QWidget,
)

from station.errors import InputError
from station.model.flakes import FLAKE_RANGES
from station.render.scene_image import BUILTIN_MESHES
from station.render.shapes import SHAPES
from ui.models.view import ENVIRONMENT_SUFFIXES, ENVIRONMENTS, FLAKE_FIELDS, ViewModel, ViewSettings
from ui.widgets.render_view import make_render_view

EXPOSURE_STEPS_PER_EV = 10
#: Width of the flakes' level-of-detail note, px (the full text is its tooltip).
FLAKE_STATUS_WIDTH = 240
#: The flake parameter boxes: view field → (label, suffix, decimals, step). Their lowest value, one step
#: below the accepted range, reads "paint default" (the field unset).
FLAKE_BOXES = {
    "flake_size_um": ("size", " µm", 0, 5.0),
    "flake_density": ("density", " /mm²", 0, 50.0),
    "flake_spread_deg": ("spread", "°", 1, 0.5),
}


class ViewPanel(QWidget):
    """Pickers above the render view; they write :class:`ViewModel` settings.

    "Load HDR…" opens a file dialog (:attr:`env_dialog`, non-modal) for any .hdr/.exr environment; a
    loaded file joins the environment picker under its file name, a file that cannot be used leaves the
    view as it was and says why in :attr:`env_status`.
    """

    def __init__(self, model: ViewModel, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.model = model
        s = model.settings
        self._build_environment_pickers(s.environment)
        self._build_shape_pickers(s.shape)
        self.exposure = QSlider(Qt.Orientation.Horizontal)
        self.exposure.setRange(-4 * EXPOSURE_STEPS_PER_EV, 4 * EXPOSURE_STEPS_PER_EV)
        self.exposure.setValue(round(s.exposure_ev * EXPOSURE_STEPS_PER_EV))
        self.exposure_label = QLabel()
        reset = QPushButton("Reset camera")
        self.stage = QCheckBox("backdrop + ground")
        self.stage.setChecked(s.stage)
        self.coat = QCheckBox("clear coat")
        self.coat.setChecked(s.coat)
        self.flakes = QCheckBox("flakes")
        self.flakes.setChecked(s.flakes)
        self.flakes.setToolTip("metallic sparkle and glints (drawn by the GL renderer in every frame)")
        self.flake_status = QLabel()
        self.flake_status.setFixedWidth(FLAKE_STATUS_WIDTH)  # its text must not resize the view
        #: Flake size, density and spread (FLAKE_BOXES), each "paint default" at its lowest value.
        self.flake_boxes = {name: self._flake_box(name, getattr(s, name)) for name in FLAKE_BOXES}
        # two rows of pickers, so the panel fits beside the designer on a 1280-pixel-wide display
        bar = QVBoxLayout()
        for row_widgets in (
            (
                QLabel("environment"),
                self.environment,
                self.load_env,
                self.env_status,
                QLabel("shape"),
                self.shape,
                QLabel("exposure"),
                self.exposure,
                self.exposure_label,
            ),
            (self.stage, self.coat, self.flakes, reset, QLabel("paint part"), self.paint_part),
            (*self.flake_boxes.values(), self.flake_status),  # a row of their own: the view fits 1280 px
        ):
            row = QHBoxLayout()
            for w in row_widgets:
                row.addWidget(w)
            row.addStretch(1)
            bar.addLayout(row)
        self.view = make_render_view(model)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(2, 2, 2, 2)
        lay.addLayout(bar)
        lay.addWidget(self.view, 1)
        self.environment.currentIndexChanged.connect(self._on_environment_picked)
        self.load_env.clicked.connect(self.env_dialog.open)
        self.env_dialog.fileSelected.connect(self.load_environment)
        self.shape.currentIndexChanged.connect(self._on_shape_picked)
        self.paint_part.currentIndexChanged.connect(self._on_part_picked)
        self.exposure.valueChanged.connect(lambda v: self.model.update(exposure_ev=v / EXPOSURE_STEPS_PER_EV))
        self.stage.toggled.connect(lambda on: self.model.update(stage=bool(on)))
        self.coat.toggled.connect(lambda on: self.model.update(coat=bool(on)))
        self.flakes.toggled.connect(lambda on: self.model.update(flakes=bool(on)))
        self.view.frame_rendered.connect(self._on_frame)
        reset.clicked.connect(lambda: self.model.update(yaw_deg=0.0, pitch_deg=0.0, zoom=1.0))
        model.events.settings.connect(self._on_settings)
        self._on_settings(s)

    def _build_environment_pickers(self, environment: str) -> None:
        """The environment picker, "Load HDR…" with its file dialog, and the status line beside them."""
        self.environment = QComboBox()
        for name in ENVIRONMENTS:
            self.environment.addItem(name, name)
        self._select_environment(environment)
        self.load_env = QPushButton("Load HDR…")
        self.env_status = QLabel()
        self.env_dialog = QFileDialog(self, "Load an environment (HDR)")
        self.env_dialog.setFileMode(QFileDialog.FileMode.ExistingFile)
        self.env_dialog.setNameFilter(
            "HDR environments (" + " ".join(f"*{x}" for x in ENVIRONMENT_SUFFIXES) + ")"
        )
        self.env_dialog.setOption(QFileDialog.Option.DontUseNativeDialog, True)

    def _build_shape_pickers(self, shape: str) -> None:
        """The shape picker (analytic shapes, then the built-in models) and the own model's part picker."""
        self.shape = QComboBox()
        self.shape.addItems(list(SHAPES))
        for name in BUILTIN_MESHES:  # the built-in models (the procedural car), loaded when picked
            self.shape.addItem(f"procedural {name} (model)", name)
        #: The own model's part painted (mesh or material name; the first item paints every part).
        self.paint_part = QComboBox()
        self.paint_part.setToolTip("the model's part painted; the others drawn as tyre, glass or chrome")
        self._parts_of: str | None = None  # the model whose parts paint_part lists
        self.shape.setCurrentText(shape)

    def _flake_box(self, name: str, value: float | None) -> QDoubleSpinBox:
        """A spin box for the view's flake field *name*, connected to the model (FLAKE_BOXES)."""
        label, suffix, decimals, step = FLAKE_BOXES[name]
        lo, hi = FLAKE_RANGES[FLAKE_FIELDS[name]]
        box = QDoubleSpinBox()
        box.setDecimals(decimals)
        box.setSingleStep(step)
        box.setRange(lo - step, hi)
        box.setSuffix(suffix)
        box.setSpecialValueText(f"{label}: paint default")
        box.setToolTip(f"flake {label}, {lo:g}–{hi:g}{suffix} (lowest: the paint type's default)")
        box.setValue(lo - step if value is None else value)
        box.valueChanged.connect(
            lambda v, n=name, bottom=lo - step: self.model.update(**{n: None if v <= bottom else float(v)})
        )
        return box

    def _select_environment(self, env: str) -> None:
        i = self.environment.findData(env)
        if i < 0:
            self.environment.addItem(Path(env).name, env)
            i = self.environment.count() - 1
        if i != self.environment.currentIndex():
            self.environment.setCurrentIndex(i)

    def _on_environment_picked(self, index: int) -> None:
        env = self.environment.itemData(index)
        if env is not None:
            self.model.update(environment=env)

    def load_environment(self, path: str) -> bool:
        """Load the .hdr/.exr file *path* into the view (the dialog's answer); False, with the reason in
        :attr:`env_status`, when the file cannot be used."""
        try:
            self.model.load_environment(path)
        except InputError as exc:
            self.env_status.setText(f"not loaded: {exc}")
            return False
        self.env_status.setText("")
        return True

    def open_model(self, path: str) -> bool:
        """Show the model in the glTF/GLB, OBJ or STL file *path* (:meth:`ViewModel.load_model`): it joins
        the shape picker under its file name and is picked; False, with the reason (naming the file) in
        :attr:`env_status`, when the file cannot be used (the view stays as it was)."""
        try:
            self.model.load_model(path)
        except InputError as exc:
            self.env_status.setText(f"model not loaded: {exc}")
            return False
        self.env_status.setText("")
        key = self.model.settings.model
        index = self.shape.findData(key)
        if index < 0:
            self.shape.addItem(f"{Path(path).name} (model)", key)
            index = self.shape.count() - 1
        self.shape.blockSignals(True)
        self.shape.setCurrentIndex(index)
        self.shape.blockSignals(False)
        return True

    def _on_shape_picked(self, index: int) -> None:
        """A built-in shape (model off) or a loaded model picked; the orbit starts over."""
        model = self.shape.itemData(index)
        orbit = {"yaw_deg": 0.0, "pitch_deg": 0.0, "zoom": 1.0}
        if model is None:
            self.model.update(shape=self.shape.itemText(index), model=None, paint_part=None, **orbit)
        elif model not in self.model.models:  # a built-in model, picked for the first time
            self.model.load_model(model)
        else:
            self.model.update(model=model, paint_part=None, **orbit)

    def _on_part_picked(self, index: int) -> None:
        """A paint part picked (item data: the name; None paints every part); a part that cannot be
        painted is named in :attr:`env_status` and the view stays as it was."""
        if index < 0 or self.model.settings.model is None:
            return
        part = self.paint_part.itemData(index)
        if part == self.model.settings.paint_part:
            return
        try:
            self.model.set_paint_part(part)
        except InputError as exc:
            self.env_status.setText(f"paint part not set: {exc}")
            return
        self.env_status.setText("")

    def _list_parts(self, s: ViewSettings) -> None:
        """The paint-part picker lists the parts of the model shown (disabled with a shape) and shows its
        paint part."""
        combo = self.paint_part
        combo.blockSignals(True)
        if s.model != self._parts_of:
            self._parts_of = s.model
            combo.clear()
            combo.addItem("every part", None)
            for name in self.model.model_parts():
                combo.addItem(name, name)
        combo.setEnabled(s.model is not None)
        index = combo.findData(s.paint_part)
        combo.setCurrentIndex(max(index, 0))
        combo.blockSignals(False)

    def _on_settings(self, s: ViewSettings) -> None:
        self.exposure_label.setText(f"{s.exposure_ev:+.1f} EV")
        self._select_environment(s.environment)
        self._list_parts(s)

    def _on_frame(self) -> None:
        """Say what the level of detail did with the flakes in the frame just drawn."""
        text = ""
        if self.model.settings.flakes:
            text = (
                (self.view.flake_report or "flakes drawn")
                if self.view.draws_flakes
                else ("flakes need the GL renderer (OpenGL 4.3)")
            )
        if self.flake_status.toolTip() != text:
            metrics = self.flake_status.fontMetrics()
            self.flake_status.setText(
                metrics.elidedText(text, Qt.TextElideMode.ElideRight, FLAKE_STATUS_WIDTH)
            )
            self.flake_status.setToolTip(text)

    def closeEvent(self, event) -> None:
        self.model.events.settings.disconnect(self._on_settings)
        self.view.close()
        super().closeEvent(event)
