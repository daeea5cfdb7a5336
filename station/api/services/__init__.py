"""Service functions (keyword-only, one module per domain): all logic behind the thin routers."""
