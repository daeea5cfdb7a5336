"""station.ingest"""
