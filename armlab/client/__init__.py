"""Python client of the control station: StationClient (REST + stream) and an Interbotix-style facade."""

from armlab.client.interbotix import InterbotixManipulatorXS, NotInterbotixArm, base_to_world
from armlab.client.station_client import StationClient, StationError, StreamFrame, unpack_frame

__all__ = ["InterbotixManipulatorXS", "NotInterbotixArm", "StationClient", "StationError", "StreamFrame", "base_to_world", "unpack_frame"]
