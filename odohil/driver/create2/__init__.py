"""The iRobot Create 2 backend: the OI link (``link``) and the ``Robot`` (``robot``)."""
