"""Seed 003: a wall-less periodic packing of discs with the CEM contact law (cem_contact,
periodic), biaxial tests of a specimen cut from it (specimen), calibration of the contact
constants to E50 and the friction angle (calibration), the time steps at which a packing stays
at rest (stability), and the study's parts and numbers (study). docs/BIAXIAL.md has the study;
engines.run.biaxial and engines.run.biaxial_study run it.
"""
