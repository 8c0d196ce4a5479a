// One calibration state, shown the same everywhere (issue 21): the status's calibration_state drives the
// Calibration panel's badge, the top bar's indicator, the click-grab/drop buttons (blocked with the reason while
// the calibration is not trusted) and the marking of detections seen through a camera the calibration no
// longer fits. The panel's state line (clickcal.js) reads the same field.

const $ = (id) => document.getElementById(id);

const TOP_TEXT = {
  trusted: "calib: trusted",
  untrusted: "calib: not trusted",
  checking: "calib: checking",
  rejected: "calib: rejected",
};

/** The calibration state of a status: 'trusted' | 'untrusted' | 'checking' | 'rejected' | 'none'. */
export function calibrationState(s) {
  if (!s) return "none";
  return s.calibration_state || (s.calibrated ? "trusted" : "none");
}

/** Why click-grab/drop and grabbing a detection are refused now ('' when they are not): the calibration's trust. */
export function untrustedReason(s) {
  const state = calibrationState(s);
  if (state !== "untrusted" && state !== "rejected") return "";
  const why = s.camera_warning ? ` (${s.camera_warning})` : "";
  return `calibration not trusted${why}: grabs and drops are refused; recalibrate`;
}

/** Badge, top-bar indicator and click-mode buttons from a status. */
export function renderCalibrationState(s) {
  const state = calibrationState(s);
  const badge = $("calib-badge");
  const calibrated = Boolean(s && s.calibrated);
  badge.dataset.ok = String(calibrated && state === "trusted");
  badge.textContent = !calibrated ? "not calibrated" : state === "trusted" ? "calibrated" : "calibrated · not trusted";
  const top = $("ind-calib");
  top.dataset.state = state;
  top.textContent = TOP_TEXT[state] || "calib: none";
  const reason = untrustedReason(s);
  top.title = reason || "Camera calibration";
  document.querySelectorAll("#click-mode [data-mode='grab'], #click-mode [data-mode='drop']").forEach((button) => {
    const ours = !button.dataset.blocked || button.dataset.blocked === button.dataset.calReason; // no-arm's block stays
    if (!ours) return;
    if (!("titleIdle" in button.dataset)) button.dataset.titleIdle = button.title || "";
    if (reason) {
      button.dataset.blocked = reason;
      button.dataset.calReason = reason;
    } else {
      delete button.dataset.blocked;
      delete button.dataset.calReason;
    }
    button.title = reason || button.dataset.titleIdle;
  });
}
