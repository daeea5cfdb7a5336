"""PySide6 workstation viewer (a client of the station core)."""
