"""station.model"""
