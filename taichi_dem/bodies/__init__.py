"""Rigid triangle-mesh bodies: prescribed motion on the host (kinematics.py) and the
particle-triangle contacts and body loads on the device (mesh_contacts.py)."""
