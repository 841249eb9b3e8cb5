"""Drivers for the rig's serial devices and their virtual twins (pseudo-terminals)."""
