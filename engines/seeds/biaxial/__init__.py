"""Seed 003: a wall-less periodic packing of discs with the CEM contact law (cem_contact,
periodic), biaxial tests of a specimen cut from it (specimen), calibration of the contact
constants to E50 and the friction angle (calibration). docs/BIAXIAL.md has the study.
"""
