"""Tests of engines/studies/ (marked studies)."""
