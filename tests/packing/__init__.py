"""Tests of packing/ (marked packing)."""
