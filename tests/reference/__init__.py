"""Tests of engines/reference/ (marked reference)."""
