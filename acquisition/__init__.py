"""Test procedures, synchronized sampling, crash-safe recording and the operator's live view."""
