"""The multi-process soak test: every front of the product on one database, killed at random."""
