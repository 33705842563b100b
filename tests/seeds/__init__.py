"""Tests of engines/seeds/ (marked seeds)."""
