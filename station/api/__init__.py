"""station.api"""
