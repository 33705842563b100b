"""Tests of postproc/ (marked postproc)."""
