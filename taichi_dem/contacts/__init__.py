"""Contacts: the geometry of one contact of each kind (sphere-sphere, sphere-plane,
sphere-triangle) and the contact law that runs the enabled contact effects on it.

``geometry.py`` turns two bodies in contact (or within an effect's margin of it) into one
``Contact`` record; ``law.py`` composes the enabled effects into one ``ti.func`` per contact
kind. The engine and the bodies only detect contacts and book the law's response.
"""
