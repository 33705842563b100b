"""Tests of engines/run/ (marked run)."""
