"""The FastAPI server: thin routes over the station (armlab.station)."""
