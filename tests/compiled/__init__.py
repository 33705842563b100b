"""Tests of engines/compiled/ (marked compiled)."""
