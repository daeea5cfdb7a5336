"""Qt widgets of the viewer; each binds to a Qt-free model from ``ui.models``."""
