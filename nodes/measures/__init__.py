"""Measurements of a result as Table outputs: what ``nodegraph sweep`` reads as metrics."""

from .particle_contacts import particle_contacts

__all__ = ["particle_contacts"]
