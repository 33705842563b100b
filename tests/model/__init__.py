"""Tests of engines/model/ (marked model)."""
