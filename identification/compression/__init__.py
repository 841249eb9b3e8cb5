"""Compression: the nominal curve, friction (barrelling, FE table, adhesion) and its corrections."""
