"""Tension: ISO 6892-1 values, the elastic line, the true curve and its neck corrections."""
