"""The sequenced robot: a sequencer switches the skills on and off, phase by phase.

`delivery` is the mission's narrative; `routes` follows a map's route hints; `behaviours`
holds what the phases share (turning, homing, lining up, passing a door, searching).
"""
