"""Device simulators: same wire protocols as the real instruments. Never imported by runtime code."""
