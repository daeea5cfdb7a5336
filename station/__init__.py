"""CACAD Station: computer aided design for colour appearance, as a lab workstation.

The core packages (``station.model``, ``station.render``, ``station.drivers`` …) hold all the science;
the CLI (:mod:`station.cli`), the FastAPI service (:mod:`station.api`) and the Qt viewer (``ui``) are
thin fronts over the same functions.
"""

__version__ = "0.1.0"

from station.lazy import defer_submodule

# colour-science imports its plotting package (and Matplotlib's pyplot) on import; no command needs it
# at start-up, so it is loaded on first use instead (about a third of colour-science's import time).
defer_submodule("colour.plotting")
