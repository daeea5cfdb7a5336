"""CACAD Station: computer aided design for colour appearance, as a lab workstation.

The core packages (``station.model``, ``station.render``, ``station.drivers`` …) hold all the science;
the CLI (:mod:`station.cli`), the FastAPI service (:mod:`station.api`) and the Qt viewer (``ui``) are
thin fronts over the same functions.
"""

__version__ = "0.1.0"
