// Operator inputs checked before anything is sent, against limits the server serves (hello.limits), and
// the reasons shown where data is missing. Pure helpers plus tiny DOM setters; no limits written here.

/** Set the move-time input's min/max from the server's limits ({min_moving_time_s, max_moving_time_s}). */
export function applyMovingTimeLimits(input, limits) {
  if (!limits) return;
  if (Number.isFinite(limits.min_moving_time_s)) input.dataset.minS = String(limits.min_moving_time_s);
  if (Number.isFinite(limits.max_moving_time_s)) input.dataset.maxS = String(limits.max_moving_time_s);
  input.title = `seconds, ${input.dataset.minS ?? "> 0"} to ${input.dataset.maxS ?? "?"} (the station's limits)`;
}

/**
 * The move time typed in `input` (seconds): {ok: true, valueS} or {ok: false, message}. Text that is not a
 * number, or a number outside the served min/max, is refused (never read as 0); empty = the station's default.
 */
export function readMovingTimeS(input) {
  const text = String(input.value ?? "").trim();
  if (text === "") return { ok: true, valueS: undefined };
  if (!/^[+]?(\d+\.?\d*|\.\d+)$/.test(text)) return { ok: false, message: `move time '${text}' is not a number of seconds` };
  const valueS = Number(text);
  const min = Number(input.dataset.minS);
  const max = Number(input.dataset.maxS);
  if (input.dataset.minS && valueS < min) return { ok: false, message: `move time must be at least ${min} s (the station's limit)` };
  if (input.dataset.maxS && valueS > max) return { ok: false, message: `move time must be at most ${max} s (the station's limit)` };
  if (!(valueS > 0)) return { ok: false, message: "move time must be more than 0 s" };
  return { ok: true, valueS };
}

/** Why the detections list is empty, from the status: not calibrated, or stale perception; '' otherwise. */
export function emptyDetectionsReason(status) {
  if (!status) return "waiting for the station…";
  if (!status.calibrated) return "No detections before calibration: press Calibrate (blocks are located through the camera's pose).";
  if (status.detections_stale) return "Detections are stale: the camera is not answering.";
  if (status.devices_lost && status.devices_lost.camera) return `Camera lost: ${status.devices_lost.camera}`;
  return "";
}
