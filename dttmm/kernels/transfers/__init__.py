"""The elements' transfer matrices over one time step: the rigid body (body.py, and em_body.py for
the energy-momentum scheme), the modal beam (beam.py), the elastic hinge (hinge.py), the joints with
coordinates (joint.py)."""
