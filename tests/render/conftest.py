"""Fixtures for the renderer tests (builders live in helpers.py)."""
