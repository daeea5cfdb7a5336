"""station.formulate"""
