"""Matplotlib figures. Modules here import matplotlib lazily, inside their functions."""
