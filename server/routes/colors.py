"""Colour calibration (armlab/station/colors.py): the operator names a block's colour by clicking it in
the newest frame, or a labelled frame's faces replace the samples; reset returns to the defaults.
Bad input (an unknown colour name, a pixel outside the image, a grey face named as a colour) is 422
naming the field, and the colour model in use is unchanged; no frame yet is 503."""

from __future__ import annotations

from fastapi import APIRouter

from server.colors_models import ColorFitRequest, ColorFitResponse, ColorSampleRequest, ColorSampleResponse, ColorsInfo
from server.deps import ControlAuth, StationDep

router = APIRouter(prefix="/api/colors", tags=["calibration"])


def newest_color_frame(station):
    """The newest camera frame's colour image; TimeoutError (503) when the camera has given none."""
    frame, _ = station.frames.get()
    if frame is None and station.synchronous:
        frame = station.fresh_frame()
    if frame is None:
        raise TimeoutError("no camera frame yet: is the camera running?")
    return frame.color_bgr


def _checked(station, controller: str):
    """The station's colour keeper, once the state and the control lease allow calibrating."""
    station.allowed_or_raise("calibrate", controller)
    return station.colors


@router.get("", response_model=ColorsInfo)
def read_colors(station: StationDep) -> dict:
    """The colour model in use: classes, names a sample may carry, the unknown threshold, the samples."""
    return station.colors.info()


@router.post("/samples", response_model=ColorSampleResponse)
def post_sample(body: ColorSampleRequest, station: StationDep, controller: ControlAuth) -> dict:
    """Name the colour of the block at (u, v) of the newest frame; used by perception at once and stored."""
    colors = _checked(station, controller)
    colors.check_name(body.color)  # before waiting for a frame: a typo is refused at once
    return colors.add_sample(newest_color_frame(station), body.u, body.v, body.color)


@router.post("/fit", response_model=ColorFitResponse)
def post_fit(body: ColorFitRequest, station: StationDep, controller: ControlAuth) -> dict:
    """Replace the samples by the listed faces of the newest frame (a labelled frame); all or none."""
    colors = _checked(station, controller)
    for i, item in enumerate(body.samples):
        colors.check_name(item.color, f"samples[{i}].color")
    return colors.fit(newest_color_frame(station), [(s.u, s.v, s.color) for s in body.samples])


@router.delete("/samples")
def delete_samples(station: StationDep, controller: ControlAuth) -> dict:
    """Back to the config's default colours (stored: a restart keeps it)."""
    return _checked(station, controller).reset()
