"""The tests: one folder per layer of the tree (conftest.py marks each test with it)."""
