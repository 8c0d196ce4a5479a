"""Wire models of the colour calibration routes (server/routes/colors.py)."""

from __future__ import annotations

from pydantic import Field

from server.wire_base import Pixel, Request, Wire

ColorName = Field(min_length=1, max_length=32, description="a colour the station knows: a class (red ... violet) or an extra name (pink, light_blue, ...)")


class ColorSampleRequest(Request):
    """A block's colour, named by the operator: the face at pixel (u, v) of the newest frame."""

    u: Pixel = Field(description="pixel column in the colour image")
    v: Pixel = Field(description="pixel row in the colour image")
    color: str = ColorName


class ColorFitRequest(Request):
    """A labelled frame: every listed face (u, v, colour) of the newest frame; replaces the station's samples."""

    samples: list[ColorSampleRequest] = Field(min_length=1, max_length=200)


class ColorSampleInfo(Wire):
    name: str
    lab: list[float] = Field(description="board-normalised CIELAB (L, a, b) measured at the click")
    u: float | None = None
    v: float | None = None
    time_s: float | None = None


class ColorReadingInfo(Wire):
    name: str = Field(description="the class the model gave ('unknown': far from every class)")
    measured_lab: list[float]
    distance: float = Field(description="to the nearest reference of that class (of `nearest` for unknown)")
    nearest: str


class ColorSampleResponse(Wire):
    sample: ColorSampleInfo
    reading_before: ColorReadingInfo = Field(description="what the colour model read there before this sample")
    samples: int = Field(description="samples in use now")


class ColorFitResponse(Wire):
    samples: int
    read_otherwise_before: int = Field(description="faces the model read as another colour before the fit")


class ColorsInfo(Wire):
    """The colour model in use: the config's defaults plus this station's samples."""

    classes: list[str]
    names: list[str] = Field(description="every colour name a sample may carry")
    max_distance: float = Field(description="a face farther than this from every reference reads 'unknown'")
    samples: list[ColorSampleInfo]
    references: dict[str, list[list[float]]] = Field(description="the defaults: CIELAB references per class")


COLOR_WIRE_MODELS = (ColorSampleRequest, ColorFitRequest, ColorSampleInfo, ColorReadingInfo, ColorSampleResponse,
                     ColorFitResponse, ColorsInfo)
