"""station.render"""
