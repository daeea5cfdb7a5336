"""station.design"""
