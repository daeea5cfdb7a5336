"""Qt-free view models of the viewer: plain Python state with observer callbacks (no Qt imports)."""
