"""Reproductions of the seed papers' tables and figures, beside the printed numbers."""
