"""Hardening laws (today's three and Johnson–Cook) and their fits."""
