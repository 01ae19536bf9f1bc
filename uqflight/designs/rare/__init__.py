"""Rare-event designs."""
