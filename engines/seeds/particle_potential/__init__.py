"""Seed 002: Saito & Fujiwara's particle-potential soil model solved by energy minimisation
(model) and the §4 uniaxial tests on its half specimen (specimen).
"""
