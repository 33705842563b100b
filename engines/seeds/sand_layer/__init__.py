"""Seed 004: the Monte-Carlo model sand layer of Matsuo, Komada & Takahashi (layer: elements filled
with grains drawn from the size distribution), its stress transmission and settlement (mechanics),
and the realisations under a strip load (study).
"""
