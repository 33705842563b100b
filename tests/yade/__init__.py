"""Tests of engines/yade/ (marked yade)."""
