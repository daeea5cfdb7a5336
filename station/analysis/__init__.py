"""station.analysis"""
