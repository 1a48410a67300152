"""Skinny's MJCF models (Menagerie layout), installed as the package data ``skinny_mj.models``."""
