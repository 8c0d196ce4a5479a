// generated, do not edit: made by `python -m server.gen_wire_types` from server/models.py and server/program_models.py.
// The wire protocol between the station server and the browser (SI units; field names carry them).
// Binary frames: [uint32 little-endian header length N][N bytes UTF-8 JSON FrameHeader][JPEG bytes].

export const STATES = Object.freeze(["idle", "calibrate", "teach", "repeat", "click_grab", "click_drop", "auto_sort", "estop", "fault"]);
export const COMMANDS = Object.freeze(["estop", "reset", "home", "sleep", "move_joints", "move_to", "jog", "torque", "gripper", "calibrate", "grab", "drop", "teach_start", "teach_record", "teach_stop", "teach_undo", "repeat", "auto", "cancel", "set_scene", "pause", "resume", "step", "set_speed"]);
export const ARM_COMMANDS = Object.freeze(["home", "sleep", "move_joints", "move_to", "jog", "torque", "gripper", "grab", "drop", "teach_start", "teach_record", "teach_stop", "teach_undo", "repeat", "auto", "pause", "resume", "step", "set_speed"]);
export const VIEWS = Object.freeze(["color", "depth", "topdown"]);
export const LAYERS = Object.freeze(["tags", "detections", "grid"]);
export const ERROR_CODES = Object.freeze(["wrong_state", "unreachable", "unsafe", "invalid", "not_found", "not_calibrated", "unauthorized", "forbidden", "not_controller", "needs_confirmation", "no_arm", "device", "disk_full", "stale_plan", "internal"]);
export const SERVER_MESSAGE_TYPES = Object.freeze(["frame", "telemetry", "event", "calibration", "hello", "jog_reply"]);
export const CLIENT_MESSAGE_TYPES = Object.freeze(["ack", "view", "command", "heartbeat", "jog", "jog_cartesian", "jog_stop"]);
export const EVENT_KINDS = Object.freeze(["general", "scene"]);

/**
 * @typedef {Object} AckMessage
 * @property {"ack"} type
 * @property {number} seq
 */

/**
 * @typedef {Object} ArmCalibrationStatus
 * @property {boolean} calibrated
 * @property {(number|null)} [residual_mm] the arm calibration's mean residual (mm) at the gripper tag
 * @property {(number|null)} [at] when it was made (time.time())
 */

/**
 * The station's arm and gripper (armlab.station.arm_info), sent once in the hello: the page builds its
 * jog sliders, joint readouts, plot and teach table from these, never from names of its own.
 * @typedef {Object} ArmInfo
 * @property {string} name config/arms/<name>.yaml
 * @property {(string|null)} [vendor] who makes the arm (interbotix, universal_robots); None = not said
 * @property {Array<string>} joint_names
 * @property {Array<Array<number>>} joint_limits_rad [lower, upper] per joint, joint_names order
 * @property {Array<number>} velocity_limits_rad_s
 * @property {Array<number>} home_rad
 * @property {("fingers"|"suction"|"none")} gripper_type
 * @property {boolean} full_pose Cartesian moves keep the tool's whole orientation (six joints or more), else pitch and yaw
 * @property {boolean} [has_arm] False: a station with no arm (armlab serve --arm none), perception only; no joints
 * @property {(string|null)} [reason] why the arm's panels are off (a station with no arm)
 */

/**
 * @typedef {Object} AutoJobInfo
 * @property {string} name
 * @property {Array<number>} levels [] = the job has no levels
 * @property {string} summary
 * @property {Array<AutoParam>} params
 * @property {boolean} judged a competition event (DESIGN §7): the simulation scores it with the judge
 * @property {boolean} scored the simulation scores it: the judge (§7), else the job's own scorer
 * @property {boolean} scene POST /api/sim/scene can generate its starting scene
 * @property {(number|null)} [time_limit_s] the event's time limit, simulated seconds
 * @property {boolean} [available] the station's workcell can run it (its gripper type and geometry)
 * @property {(string|null)} [unavailable_reason] why not, when not available: what the workcell lacks
 */

/**
 * @typedef {Object} AutoJobsResponse
 * @property {Array<AutoJobInfo>} data
 * @property {number} count
 */

/**
 * @typedef {Object} AutoParam
 * @property {string} name
 * @property {string} type Python type name: int, float, str, bool, list, ...
 */

/**
 * Start an autonomous job: a name from GET /api/auto/jobs, one of its levels, its parameters.
 * @typedef {Object} AutoRequest
 * @property {string} job job name (GET /api/auto/jobs)
 * @property {(number|null)} [level] one of the job's levels; None = its highest
 * @property {(Object<string, *>|null)} [params] job parameters by name, each of the type GET /api/auto/jobs gives
 */

/**
 * @typedef {Object} AutoResponse
 * @property {JobInfo} job
 * @property {(AutoScoreResponse|null)} [score] with ?wait=true in the simulation: the final score
 */

/**
 * @typedef {Object} AutoScore
 * @property {number} points
 * @property {number} max_points
 * @property {boolean} within_limit
 * @property {boolean} full
 * @property {number} time_limit_s
 * @property {Array<ScoreRule>} breakdown
 */

/**
 * The judge's score of the last autonomous job started over the API (simulation only).
 * @typedef {Object} AutoScoreResponse
 * @property {string} job_id
 * @property {string} job
 * @property {(number|null)} level
 * @property {("running"|"succeeded"|"failed"|"cancelled")} state
 * @property {boolean} final True once the job has ended and its final ground truth was scored
 * @property {number} sim_time_s simulated seconds from the job's start to its end (so far, while running)
 * @property {(AutoScore|null)} [score] None while running, or for a job the judge does not score
 * @property {string} [note]
 */

/**
 * @typedef {Object} BinInfo
 * @property {Array<number>} x_range_m
 * @property {Array<number>} y_range_m
 */

/**
 * @typedef {Object} BoardInfo
 * @property {Array<number>} x_range_m [x_min, x_max] of the board, world frame, metres
 * @property {Array<number>} y_range_m [y_min, y_max] of the board, world frame, metres
 * @property {GridInfo} grid
 */

/**
 * @typedef {Object} BoardTagsInfo
 * @property {string} family
 * @property {number} size_m
 * @property {Object<string, *>} centres_m tag id -> [x, y] of its centre, metres
 */

/**
 * @typedef {Object} CalibrationInfo
 * @property {boolean} calibrated
 * @property {(number|null)} [reprojection_error_px]
 * @property {(Array<number>|null)} [camera_position_m]
 * @property {(Array<Array<number>>|null)} [T_world_camera]
 * @property {(Array<Array<number>>|null)} [K]
 * @property {(Array<number>|null)} [dist]
 * @property {(number|null)} [width]
 * @property {(number|null)} [height]
 * @property {(number|null)} [depth_check_error_m]
 * @property {(number|null)} [depth_offset_m] the depth camera's board plane above (+) or behind (-) the tags' plane
 * @property {(number|null)} [depth_tilt_deg] angle between the depth camera's board plane and the tags' plane
 * @property {(string|null)} [depth_model] the two in words, e.g. 'depth 8.3 mm behind the tags' plane, tilted 1.52 deg'
 * @property {(Array<Array<number>>|null)} [grid_points_px]
 * @property {(Array<TagInfo>|null)} [tags]
 * @property {(number|null)} [time]
 * @property {(string|null)} [method] 'points' for a calibration from clicked points, 'arm-camera' from the arm's gripper tag (tags otherwise)
 * @property {(Object<string, *>|null)} [points] clicked-point fit: homography, reprojection and per-point errors (px)
 */

/**
 * @typedef {Object} CalibrationMessage
 * @property {boolean} calibrated
 * @property {(number|null)} [reprojection_error_px]
 * @property {(Array<number>|null)} [camera_position_m]
 * @property {(Array<Array<number>>|null)} [T_world_camera]
 * @property {(Array<Array<number>>|null)} [K]
 * @property {(Array<number>|null)} [dist]
 * @property {(number|null)} [width]
 * @property {(number|null)} [height]
 * @property {(number|null)} [depth_check_error_m]
 * @property {(number|null)} [depth_offset_m] the depth camera's board plane above (+) or behind (-) the tags' plane
 * @property {(number|null)} [depth_tilt_deg] angle between the depth camera's board plane and the tags' plane
 * @property {(string|null)} [depth_model] the two in words, e.g. 'depth 8.3 mm behind the tags' plane, tilted 1.52 deg'
 * @property {(Array<Array<number>>|null)} [grid_points_px]
 * @property {(Array<TagInfo>|null)} [tags]
 * @property {(number|null)} [time]
 * @property {(string|null)} [method] 'points' for a calibration from clicked points, 'arm-camera' from the arm's gripper tag (tags otherwise)
 * @property {(Object<string, *>|null)} [points] clicked-point fit: homography, reprojection and per-point errors (px)
 * @property {"calibration"} [type]
 */

/**
 * Hold-to-run Cartesian jog: the gripper point moves along world x|y|z at velocity_m_s (signed; its top speed is
 * the station's jog_max_speed_m_s, scaled by speed_percent) keeping its pitch and yaw, for jog_hold_s after each
 * heartbeat, then brakes to rest by itself; where the line cannot go on it stops before it (422 when it cannot move).
 * @typedef {Object} CartesianJogRequest
 * @property {("x"|"y"|"z")} axis the world axis the gripper point moves along
 * @property {number} velocity_m_s metres per second along the axis (+ or −); 0 ramps down to rest
 * @property {number} [speed_percent] speed override, % of the configured speed (10-100)
 */

/**
 * A labelled frame: every listed face (u, v, colour) of the newest frame; replaces the station's samples.
 * @typedef {Object} ColorFitRequest
 * @property {Array<ColorSampleRequest>} samples
 */

/**
 * @typedef {Object} ColorFitResponse
 * @property {number} samples
 * @property {number} read_otherwise_before faces the model read as another colour before the fit
 */

/**
 * @typedef {Object} ColorReadingInfo
 * @property {string} name the class the model gave ('unknown': far from every class)
 * @property {Array<number>} measured_lab
 * @property {number} distance to the nearest reference of that class (of `nearest` for unknown)
 * @property {string} nearest
 */

/**
 * @typedef {Object} ColorSampleInfo
 * @property {string} name
 * @property {Array<number>} lab board-normalised CIELAB (L, a, b) measured at the click
 * @property {(number|null)} [u]
 * @property {(number|null)} [v]
 * @property {(number|null)} [time_s]
 */

/**
 * A block's colour, named by the operator: the face at pixel (u, v) of the newest frame.
 * @typedef {Object} ColorSampleRequest
 * @property {number} u pixel column in the colour image
 * @property {number} v pixel row in the colour image
 * @property {string} color a colour the station knows: a class (red ... violet) or an extra name (pink, light_blue, ...)
 */

/**
 * @typedef {Object} ColorSampleResponse
 * @property {ColorSampleInfo} sample
 * @property {ColorReadingInfo} reading_before what the colour model read there before this sample
 * @property {number} samples samples in use now
 */

/**
 * The colour model in use: the config's defaults plus this station's samples.
 * @typedef {Object} ColorsInfo
 * @property {Array<string>} classes
 * @property {Array<string>} names every colour name a sample may carry
 * @property {number} max_distance a face farther than this from every reference reads 'unknown'
 * @property {Array<ColorSampleInfo>} samples
 * @property {Object<string, *>} references the defaults: CIELAB references per class
 */

/**
 * @typedef {Object} CommandMessage
 * @property {"command"} type
 * @property {("estop"|"reset"|"cancel"|"take_control"|"release_control")} name
 */

/**
 * POST /api/teach/continuous: trajectory mode, recording the pose at rate_hz while it changes.
 * @typedef {Object} ContinuousRequest
 * @property {number} rate_hz records per second (0.5-20)
 * @property {number} [min_change_rad] record only when a joint moved this much (or the gripper changed)
 */

/**
 * @typedef {Object} ContinuousResponse
 * @property {boolean} recording
 * @property {(number|null)} [rate_hz]
 * @property {number} recorded waypoints this recording added
 * @property {number} count waypoints in the draft now
 */

/**
 * @typedef {Object} Detection
 * @property {number} id
 * @property {(string|null)} color
 * @property {(string|null)} size
 * @property {Array<number>} position_m top face centre, world frame
 * @property {number} yaw_rad
 * @property {number} height_m
 * @property {number} stack_level
 * @property {Array<number>} center_px
 * @property {boolean} is_cube
 * @property {boolean} occluded
 * @property {(number|null)} [aruco_id]
 * @property {*} [destination]
 * @property {(Array<number>|null)} [color_lab] the top face's colour, board-normalised CIELAB (L, a, b): what an 'unknown' colour measured
 */

/**
 * @typedef {Object} DetectionsResponse
 * @property {Array<Detection>} data
 * @property {number} count
 * @property {number} time_s
 * @property {number} frame_sequence
 * @property {boolean} [stale] True while the camera is lost or perception is old: data is then empty
 * @property {(string|null)} [stale_reason]
 */

/**
 * @typedef {Object} DuplicateRequest
 * @property {(string|null)} [name] the copy's name; None = '<name> (copy)'
 */

/**
 * @typedef {Object} ErrorBody
 * @property {string} code
 * @property {string} message
 * @property {(Array<string>|null)} [allowed]
 * @property {(string|null)} [reason] why a plan is stale (stale_plan): executed, expired, arm_moved, arm_commanded, ...
 * @property {(string|null)} [part] the joint or part of the arm a refused motion names (unsafe); GET /api/view3d/scene's arm.part_links names its links
 * @property {(Array<number>|null)} [at_q_rad] the joints (rad) at the refused motion's first offending sample (unsafe)
 */

/**
 * @typedef {Object} ErrorResponse
 * @property {ErrorBody} error
 */

/**
 * An operator event. The page acts on `kind` (armlab.station.slots.EventLog.KINDS), never on the text.
 * @typedef {Object} EventMessage
 * @property {"event"} [type]
 * @property {("info"|"warn"|"error")} level
 * @property {("general"|"scene")} kind what happened, for a client to act on; 'general': for people only
 * @property {string} message
 * @property {number} time_s
 */

/**
 * Header of a binary frame: [uint32 LE header length N][N bytes of this JSON][JPEG bytes].
 * @typedef {Object} FrameHeader
 * @property {"frame"} [type]
 * @property {number} seq
 * @property {number} capture_time_s time.time() at capture
 * @property {number} width
 * @property {number} height
 * @property {("color"|"depth"|"topdown")} view
 */

/**
 * @typedef {Object} GridInfo
 * @property {Array<number>} x_m first and last grid point x, metres
 * @property {Array<number>} y_m first and last grid point y, metres
 * @property {number} step_m
 */

/**
 * @typedef {Object} GripperPose
 * @property {Array<number>} position_m
 * @property {number} pitch_rad
 * @property {number} yaw_rad
 */

/**
 * @typedef {Object} GripperRequest
 * @property {("grasp"|"release")} action
 */

/**
 * @typedef {Object} GripperStatus
 * @property {number} width_m
 * @property {boolean} holding
 * @property {string} command
 */

/**
 * Open or close the gripper at the pose of the waypoint before it.
 * @typedef {Object} GripperStepRequest
 * @property {"gripper"} kind
 * @property {("open"|"close")} action
 */

/**
 * A labelled group of steps (run once).
 * @typedef {Object} GroupStepRequest
 * @property {"group"} kind
 * @property {string} label
 * @property {Array<(WaypointStepRequest|WaitStepRequest|GripperStepRequest|LoopStepRequest|GroupStepRequest)>} body
 */

/**
 * The controlling page is still there: keeps its hold-to-run jog going for another jog_hold_s.
 * @typedef {Object} HeartbeatMessage
 * @property {"heartbeat"} type
 */

/**
 * @typedef {Object} HelloMessage
 * @property {"hello"} [type]
 * @property {number} server_time_s
 * @property {boolean} can_control
 * @property {(string|null)} [controller] this session's controller name (the lease holder's name when it commands)
 * @property {("sim"|"real")} backend
 * @property {WorkcellInfo} workcell
 * @property {ArmInfo} arm
 * @property {(LimitsInfo|null)} [limits]
 */

/**
 * POST /api/programs/import/file: the stored program and how the file became it.
 * @typedef {Object} ImportFileResponse
 * @property {number} id
 * @property {string} name
 * @property {number} created_s
 * @property {(number|null)} [updated_s]
 * @property {(string|null)} [arm] the arm it was taught on (None: saved before programs had an arm)
 * @property {(string|null)} [workcell] the workcell it was taught in (None: saved before programs had one)
 * @property {Array<WaypointInfo>} waypoints the flat sequence repeat runs (a step tree expanded)
 * @property {(Array<Object<string, *>>|null)} [steps] the step tree (waypoints, wait, gripper, loop, group); None: waypoints only
 * @property {Array<string>} [notes] what the import read and did, one line each (topic, gripper source, thinning)
 * @property {Object<string, *>} [clamped_rad] joints clamped into their limits: the largest correction, rad
 * @property {number} [clamped_samples] samples clamped (only with clamp_rad)
 * @property {number} [samples] joint samples read (0: a CSV or JSON program)
 */

/**
 * POST /api/programs/import: a file's text as exported (JSON or CSV `t_s, q1..qn, gripper`).
 * @typedef {Object} ImportRequest
 * @property {("json"|"csv")} format
 * @property {string} content the file's text
 * @property {(string|null)} [name] the program's name; None = the JSON's name, else 'imported'
 */

/**
 * @typedef {Object} JobInfo
 * @property {string} id
 * @property {string} name
 * @property {string} [detail]
 * @property {("running"|"succeeded"|"failed"|"cancelled")} state
 * @property {number} progress
 * @property {string} message
 * @property {number} started_s
 * @property {(number|null)} [finished_s]
 * @property {*} [result]
 * @property {(Object<string, *>|null)} [extra] job-specific live details; autonomous jobs: {task: TaskProgress}
 */

/**
 * @typedef {Object} JobResponse
 * @property {(JobInfo|null)} job
 */

/**
 * Start (or keep going) a hold-to-run Cartesian jog, as POST /api/arm/jog/cartesian; answered by a jog_reply.
 * @typedef {Object} JogCartesianMessage
 * @property {("x"|"y"|"z")} axis the world axis the gripper point moves along
 * @property {number} velocity_m_s metres per second along the axis (+ or −); 0 ramps down to rest
 * @property {number} [speed_percent] speed override, % of the configured speed (10-100)
 * @property {"jog_cartesian"} type
 * @property {(number|null)} [id] echoed in the jog_reply, so the page knows which request it answers
 */

/**
 * Start (or keep going) a hold-to-run joint jog, as POST /api/arm/jog; answered by a jog_reply.
 * @typedef {Object} JogMessage
 * @property {Array<number>} velocity_rad_s joint velocities, joint_names order; zeros stop
 * @property {number} [speed_percent] speed override, % of the configured speed (10-100)
 * @property {"jog"} type
 * @property {(number|null)} [id] echoed in the jog_reply, so the page knows which request it answers
 */

/**
 * The answer to a jog, jog_cartesian or jog_stop message: ok, or the HTTP status and error code the REST route
 * would give (422 invalid / unreachable / unsafe, 409 not_controller / wrong_state, ...) and the reason.
 * @typedef {Object} JogReplyMessage
 * @property {"jog_reply"} [type]
 * @property {(number|null)} [id]
 * @property {boolean} ok
 * @property {number} [status_code] what the REST route answers for the same request
 * @property {(string|null)} [code] the error code (ErrorBody.code) when not ok
 * @property {(string|null)} [message]
 */

/**
 * Hold-to-run jog: joint velocities kept for jog_hold_s after each heartbeat (this request, or a
 * heartbeat), then the arm ramps to rest by itself.
 * @typedef {Object} JogRequest
 * @property {Array<number>} velocity_rad_s joint velocities, joint_names order; zeros stop
 * @property {number} [speed_percent] speed override, % of the configured speed (10-100)
 */

/**
 * The held button or key was let go: this session's controller's jog ramps down now (POST /api/arm/jog/stop).
 * @typedef {Object} JogStopMessage
 * @property {"jog_stop"} type
 * @property {(number|null)} [id] echoed in the jog_reply, so the page knows which request it answers
 */

/**
 * @typedef {Object} JointsRequest
 * @property {Array<number>} q_rad joint positions, radians, in joint_names order
 * @property {(number|null)} [moving_time_s] move duration; None = as fast as the limits allow
 */

/**
 * Limits of operator inputs, from the station's config (the page checks inputs against these).
 * @typedef {Object} LimitsInfo
 * @property {number} max_moving_time_s longest manual move accepted (moving_time_s is in (0, this])
 * @property {(number|null)} [jog_max_speed_rad_s] fastest hold-to-run joint jog at 100 % (each joint's own limit caps it)
 * @property {(number|null)} [jog_hold_s] a hold-to-run jog brakes this long after the controller's last heartbeat
 * @property {(number|null)} [jog_max_speed_m_s] fastest hold-to-run Cartesian jog of the gripper point at 100 %
 * @property {(number|null)} [jog_accel_m_s2] the Cartesian jog's ramp (and braking) acceleration
 */

/**
 * Run `body` `count` times (1-1000).
 * @typedef {Object} LoopStepRequest
 * @property {"loop"} kind
 * @property {number} count how many times the body runs (1-1000)
 * @property {Array<(WaypointStepRequest|WaitStepRequest|GripperStepRequest|LoopStepRequest|GroupStepRequest)>} body
 */

/**
 * What a joint or pose move would do, checked like the move itself; nothing moved (POST /api/arm/pose/check, /api/arm/joints/check).
 * @typedef {Object} MoveCheck
 * @property {Array<number>} q_rad the goal joints, radians, joint_names order
 * @property {number} duration_s the planned move's duration from where the arm is now
 * @property {GripperPose} gripper_pose the gripper at the goal (commanded kinematics)
 */

/**
 * A motion planned and checked as the move itself would be, moving nothing (POST /api/arm/pose or /api/arm/joints
 * with ?plan_only=true). POST /api/plans/{plan_id}/execute sends exactly this trajectory; it is refused once the plan
 * is stale (stale_when).
 * @typedef {Object} MovePlan
 * @property {string} plan_id the plan's id, for POST /api/plans/{plan_id}/execute and DELETE /api/plans/{plan_id}
 * @property {string} command the station command it executes as (move_joints, move_to, home, sleep, jog: a jog step; grab, drop: a job of several motions and gripper steps; repeat: a repeat's motions; step: a paused job's next step)
 * @property {(string|null)} controller the controller that made it: only it may execute it
 * @property {Array<number>} goal_q_rad the goal joints, radians, joint_names order (grab, drop: where the gripper grasps or releases)
 * @property {number} duration_s the trajectory's duration at the speed override it was planned at
 * @property {Array<number>} times_s sample times of the trajectory (decimated for showing; first and last kept)
 * @property {Array<Array<number>>} q_rad the joints at times_s, radians
 * @property {Array<Array<number>>} gripper_path_m the gripper point at times_s, world frame, metres
 * @property {GripperPose} gripper_pose the gripper at the goal (commanded kinematics)
 * @property {number} speed_percent the speed override it was planned at
 * @property {number} created_s when it was made (Unix seconds)
 * @property {number} expires_s when it expires (Unix seconds)
 * @property {Array<string>} stale_when what makes the station refuse it
 * @property {Array<string>} [steps] grab, drop: the job's steps in order (motions and gripper actions; the trajectory joins the motions); empty for a single move
 */

/**
 * Programs in the same database that belong to another arm or workcell (not listed: their joints mean nothing here).
 * @typedef {Object} OtherPrograms
 * @property {(string|null)} arm None: saved before programs had an arm, with another number of joints
 * @property {(string|null)} workcell
 * @property {number} count
 */

/**
 * @typedef {Object} PixelRequest
 * @property {number} u pixel column in the colour image
 * @property {number} v pixel row in the colour image
 */

/**
 * on: 'depth' (the newest frame, the robot's own readings left out), 'remembered' (under the arm: the
 * depth last seen there without it) or 'board' (the viewing ray meets z = 0).
 * @typedef {Object} PixelToWorldResponse
 * @property {Array<number>} position_m
 * @property {("board"|"depth"|"remembered")} on
 * @property {(number|null)} [depth_mm] the raw depth reading at the pixel, mm (0: no reading; None: no depth image)
 */

/**
 * DELETE /api/plans/{plan_id}: the plan is gone; executing it is then refused (404).
 * @typedef {Object} PlanDiscarded
 * @property {string} plan_id
 * @property {boolean} [discarded]
 */

/**
 * Optional body of /api/arm/home and /api/arm/sleep.
 * @typedef {Object} PoseNameRequest
 * @property {(number|null)} [moving_time_s]
 */

/**
 * @typedef {Object} PoseRequest
 * @property {Array<number>} position_m gripper point in the world (board) frame
 * @property {(number|null)} [pitch_rad] approach angle below horizontal; +π/2 = straight down; None = steepest
 * @property {(number|null)} [yaw_rad] block yaw in the world frame the fingers align with
 * @property {(number|null)} [moving_time_s]
 */

/**
 * @typedef {Object} ProgramInfo
 * @property {number} id
 * @property {string} name
 * @property {number} created_s
 * @property {(number|null)} [updated_s]
 * @property {(string|null)} [arm] the arm it was taught on (None: saved before programs had an arm)
 * @property {(string|null)} [workcell] the workcell it was taught in (None: saved before programs had one)
 * @property {Array<WaypointInfo>} waypoints the flat sequence repeat runs (a step tree expanded)
 * @property {(Array<Object<string, *>>|null)} [steps] the step tree (waypoints, wait, gripper, loop, group); None: waypoints only
 */

/**
 * PATCH /api/programs/{id}: a new name and/or the whole new waypoint list (reorder, edit a value,
 * insert or delete a waypoint or a gripper step: send the list as it should be), or the whole step tree
 * (waypoints, waits, gripper steps, loops, labelled groups; at most 4 deep, at most 1000 waypoints once
 * expanded). Checked against the joint limits and the table before anything is stored.
 * @typedef {Object} ProgramUpdateRequest
 * @property {(string|null)} [name]
 * @property {(Array<WaypointRequest>|null)} [waypoints]
 * @property {(Array<(WaypointStepRequest|WaitStepRequest|GripperStepRequest|LoopStepRequest|GroupStepRequest)>|null)} [steps] the program's step tree (replaces waypoints; a tree of waypoints only is a flat program)
 */

/**
 * GET /api/programs: this station's arm's (and workcell's) programs.
 * @typedef {Object} ProgramsResponse
 * @property {Array<ProgramInfo>} data
 * @property {number} count
 * @property {Array<string>} [skipped] damaged rows left out of data, one line each (also logged)
 * @property {number} [others_count] programs of other arms or workcells in the same database (not in data)
 * @property {Array<OtherPrograms>} [others] those programs, counted by arm and workcell
 */

/**
 * One recording: an MCAP file in Foxglove's schemas (joint states, gripper, transforms, camera, detections, events).
 * @typedef {Object} RecordingInfo
 * @property {string} id e.g. 20261203T100000Z-a1b2c3 (its UTC start time)
 * @property {string} [label]
 * @property {(string|null)} [source] who started it (the controller's name)
 * @property {string} started_utc
 * @property {string} state recording, finished or damaged
 * @property {(string|null)} [stop_reason] why it ended: stopped, disk full, budget reached, cut short, ...
 * @property {number} duration_s
 * @property {number} size_bytes
 * @property {boolean} complete the file was closed with MCAP's summary
 * @property {boolean} truncated cut short (the station was killed): readable up to its last complete chunk
 * @property {Object<string, *>} topics messages per topic
 * @property {Array<string>} jobs the jobs that ran while it recorded
 * @property {Array<string>} [states] the station's states while it recorded (idle, teach, repeat, auto_sort, ...), in order
 * @property {(string|null)} [sampler_error]
 */

/**
 * @typedef {Object} RecordingResponse
 * @property {RecordingInfo} recording
 */

/**
 * Start recording the station to MCAP (one recording at a time).
 * @typedef {Object} RecordingStartRequest
 * @property {string} [label] what is recorded, for the list (e.g. 'teach: stack of three')
 */

/**
 * @typedef {Object} RecordingsResponse
 * @property {Array<RecordingInfo>} data
 * @property {number} count
 * @property {(RecordingInfo|null)} active the recording running now, if any
 * @property {string} directory
 * @property {number} total_bytes
 * @property {number} budget_bytes
 */

/**
 * job.extra.repeat of a running repeat (also on the websocket's telemetry).
 * @typedef {Object} RepeatProgress
 * @property {number} program_id
 * @property {number} cycle the cycle running, 1-based
 * @property {(number|null)} cycles None = until stopped
 * @property {number} waypoint the waypoint last reached, 1-based
 * @property {number} waypoints
 * @property {("ease in"|"cycle"|"home"|"paused")} phase
 * @property {boolean} paused
 * @property {number} speed_percent
 * @property {number} cycle_s one cycle at this speed, seconds
 * @property {(number|null)} time_left_s None while easing in or when repeating until stopped
 * @property {Array<number>} last_cycle_times_s the durations of the last cycles (at most 5)
 * @property {number} blended_runs runs that pass through waypoints without stopping
 * @property {number} runs
 */

/**
 * @typedef {Object} RepeatRequest
 * @property {(number|null)} [cycles] how many cycles; None = until stopped (cancel)
 * @property {(number|null)} [speed_percent] speed override (10-100 %); None = the station's (GET /api/speed); a number becomes the station's override
 */

/**
 * One object of an explicit scene, in the ground-truth format (quat_wxyz wins over yaw_rad).
 * @typedef {Object} SceneObjectRequest
 * @property {string} id
 * @property {("block"|"semicircle"|"arch"|"triangle"|"cylinder")} type
 * @property {("red"|"orange"|"yellow"|"green"|"blue"|"violet")} color
 * @property {(("large"|"small")|null)} [size] blocks: large (default) or small; distractors: None = large
 * @property {Array<number>} position_m body centre, world frame
 * @property {(number|null)} [yaw_rad]
 * @property {(Array<number>|null)} [quat_wxyz] orientation (w, x, y, z), non-zero; normalised by the station
 * @property {(number|null)} [aruco_id] ArUco tag (DICT_4X4_250) on a block's top face
 */

/**
 * A generated competition scene (event, level, seed) or explicit objects (ground-truth format).
 * @typedef {Object} SceneRequest
 * @property {(("pick_sort"|"pick_stack"|"line_up"|"stack_high"|"to_the_sky"|"sort_stack"|"sort_by_tag"|"clear_table")|null)} [event] a competition event or another job with a scene generator
 * @property {(number|null)} [level]
 * @property {(number|null)} [seed]
 * @property {(Array<SceneObjectRequest>|null)} [objects]
 */

/**
 * @typedef {Object} ScoreRule
 * @property {string} rule
 * @property {number} points
 * @property {string} detail
 * @property {Array<string>} object_ids
 */

/**
 * PUT /api/speed, PATCH /api/jobs/current: the station's speed override (takes effect at once, smoothly).
 * @typedef {Object} SpeedRequest
 * @property {number} speed_percent speed override, % of full speed (10-100)
 */

/**
 * @typedef {Object} Status
 * @property {("idle"|"calibrate"|"teach"|"repeat"|"click_grab"|"click_drop"|"auto_sort"|"estop"|"fault")} state
 * @property {string} detail
 * @property {Array<number>} joints_rad
 * @property {(Array<number>|null)} [commanded_joints_rad] the commanded reference now (the last trajectory sent, at the station's clock; its end once it has run out): the measured joints trail it; None before any motion was sent or after a halt
 * @property {Array<string>} joint_names
 * @property {Array<Array<number>>} joint_limits_rad [lower, upper] per joint
 * @property {GripperStatus} gripper
 * @property {(GripperPose|null)} gripper_pose the gripper's pose (FK of the joints); None on a station with no arm
 * @property {boolean} moving
 * @property {boolean} [torque_enabled] motor torque on (the arm holds); off = limp, it falls unless held
 * @property {boolean} calibrated
 * @property {(string|null)} [camera_warning] "camera moved: recalibrate (...)" when the board tags no longer sit where the calibration puts them
 * @property {(("checking"|"trusted"|"untrusted"|"rejected")|null)} [calibration_state] trusted: in use; untrusted: in use, but the board tags do not confirm it (camera_warning says why): grabs, drops and jobs are refused; checking: restored at start, not used until the board tags confirm it; rejected: restored but the camera moved since (recalibrate); None: no calibration
 * @property {(ArmCalibrationStatus|null)} [arm_calibration] the arm's calibration from the camera (POST /api/calibrate/arm); None on a station with no arm
 * @property {boolean} [self_recalibrate] the station recalibrates itself from the board tags when idle once the camera moved (PUT /api/calibration/settings)
 * @property {("sim"|"real")} backend
 * @property {(string|null)} controller who holds the control lease (None: free); only it may command
 * @property {(number|null)} [controller_since_s] when it took control (time.time())
 * @property {Object<string, *>} [devices_lost] devices not answering, with the reason
 * @property {number} [speed_percent] the speed override (PUT /api/speed), % of full speed, of every motion
 * @property {(JobInfo|null)} job
 * @property {Array<string>} allowed_commands
 * @property {number} time_s
 */

/**
 * A jog step of the gripper: distance_m along world x|y|z keeping its pitch and yaw (within 0.5°,
 * the point within 1 mm of the line), or angle_rad of pitch (about the gripper point) or wrist roll.
 * @typedef {Object} StepRequest
 * @property {("x"|"y"|"z"|"pitch"|"roll")} axis
 * @property {(number|null)} [distance_m] metres along the world axis (x, y, z); non-zero
 * @property {(number|null)} [angle_rad] radians of pitch (+ = down) or roll; non-zero
 * @property {number} [speed_percent] speed override, % of the configured speed (10-100)
 */

/**
 * @typedef {Object} TagInfo
 * @property {number} id
 * @property {Array<number>} center_px
 * @property {Array<Array<number>>} corners_px
 * @property {(number|null)} [hamming] bits the decoder corrected (None: an OpenCV ArUco dictionary does not say)
 * @property {(number|null)} [decision_margin] the AprilTag library's confidence (higher is surer; None for ArUco)
 */

/**
 * A grab or drop target checked as the command would plan it, nothing moved (POST /api/grab/check,
 * /api/drop/check): what it would do. A refusal is the command's own error (422 unreachable/unsafe, 409).
 * @typedef {Object} TargetCheckResponse
 * @property {boolean} [ok]
 * @property {string} detail what the command would do, e.g. 'grab large red block at (120, 250) mm'
 */

/**
 * A grab/drop target: a world point, or a pixel of the colour image (exactly one).
 * @typedef {Object} TargetRequest
 * @property {(Array<number>|null)} [position_m]
 * @property {(number|null)} [u]
 * @property {(number|null)} [v]
 */

/**
 * job.extra.task of a running autonomous job (also on the websocket's telemetry).
 * @typedef {Object} TaskProgress
 * @property {number} done
 * @property {number} left
 * @property {string} step
 * @property {number} attempts
 * @property {Array<string>} failures
 * @property {number} moves
 * @property {(Detection|null)} [next_block] the block being moved (a detection)
 * @property {(Array<number>|null)} [next_target_m] where it goes: bottom-centre x, y and surface z, world frame
 */

/**
 * The waypoints recorded and not yet saved (kept on disk: a restarted station resumes them on teach/start).
 * @typedef {Object} TeachDraftResponse
 * @property {Array<WaypointInfo>} waypoints
 * @property {number} count
 * @property {Array<string>} [skipped]
 */

/**
 * Optional body of POST /api/teach/record: the waypoint's dwell and the time of the move into it.
 * @typedef {Object} TeachRecordRequest
 * @property {number} [dwell_s] seconds to hold still at the waypoint
 * @property {(number|null)} [moving_time_s] least time of the move into this waypoint at 100 %; None = as fast as allowed
 */

/**
 * The recorded waypoint (committed to the draft on disk before this answer) and the draft's size.
 * @typedef {Object} TeachRecordResponse
 * @property {Array<number>} joints_rad
 * @property {("grasp"|"release")} gripper
 * @property {number} [dwell_s]
 * @property {(number|null)} [moving_time_s]
 * @property {(Array<number>|null)} [gripper_position_m] the gripper point at these joints (FK), world frame: project it through the calibration to draw the path
 * @property {number} count waypoints in the draft now
 */

/**
 * Optional body of POST /api/teach/start: an unsaved draft (from a stopped or killed station) is resumed unless discard_draft.
 * @typedef {Object} TeachStartRequest
 * @property {boolean} [discard_draft] start with no waypoints, dropping an unsaved draft
 */

/**
 * @typedef {Object} TeachStopRequest
 * @property {string} name
 */

/**
 * @typedef {Object} TeachUndoResponse
 * @property {(WaypointInfo|null)} [removed] the waypoint taken off the end (None: the draft was empty)
 * @property {number} count
 */

/**
 * @typedef {Object} TelemetryMessage
 * @property {("idle"|"calibrate"|"teach"|"repeat"|"click_grab"|"click_drop"|"auto_sort"|"estop"|"fault")} state
 * @property {string} detail
 * @property {Array<number>} joints_rad
 * @property {(Array<number>|null)} [commanded_joints_rad] the commanded reference now (the last trajectory sent, at the station's clock; its end once it has run out): the measured joints trail it; None before any motion was sent or after a halt
 * @property {Array<string>} joint_names
 * @property {Array<Array<number>>} joint_limits_rad [lower, upper] per joint
 * @property {GripperStatus} gripper
 * @property {(GripperPose|null)} gripper_pose the gripper's pose (FK of the joints); None on a station with no arm
 * @property {boolean} moving
 * @property {boolean} [torque_enabled] motor torque on (the arm holds); off = limp, it falls unless held
 * @property {boolean} calibrated
 * @property {(string|null)} [camera_warning] "camera moved: recalibrate (...)" when the board tags no longer sit where the calibration puts them
 * @property {(("checking"|"trusted"|"untrusted"|"rejected")|null)} [calibration_state] trusted: in use; untrusted: in use, but the board tags do not confirm it (camera_warning says why): grabs, drops and jobs are refused; checking: restored at start, not used until the board tags confirm it; rejected: restored but the camera moved since (recalibrate); None: no calibration
 * @property {(ArmCalibrationStatus|null)} [arm_calibration] the arm's calibration from the camera (POST /api/calibrate/arm); None on a station with no arm
 * @property {boolean} [self_recalibrate] the station recalibrates itself from the board tags when idle once the camera moved (PUT /api/calibration/settings)
 * @property {("sim"|"real")} backend
 * @property {(string|null)} controller who holds the control lease (None: free); only it may command
 * @property {(number|null)} [controller_since_s] when it took control (time.time())
 * @property {Object<string, *>} [devices_lost] devices not answering, with the reason
 * @property {number} [speed_percent] the speed override (PUT /api/speed), % of full speed, of every motion
 * @property {(JobInfo|null)} job
 * @property {Array<string>} allowed_commands
 * @property {number} time_s
 * @property {"telemetry"} [type]
 * @property {Array<Detection>} detections
 * @property {boolean} [detections_stale]
 */

/**
 * @typedef {Object} TorqueRequest
 * @property {boolean} enabled
 * @property {boolean} [confirm] torque off outside teach lets the arm fall: needs confirm: true
 */

/**
 * GET /api/jobs/current/trace: commanded and measured joints over the last complete cycle of the
 * repeat (the running one until a cycle has completed). samples: [t_s, commanded × dof, measured × dof].
 * @typedef {Object} TraceResponse
 * @property {string} job_id
 * @property {number} cycle
 * @property {boolean} complete
 * @property {Array<string>} joint_names
 * @property {Array<string>} columns
 * @property {Array<Array<number>>} samples
 */

/**
 * @typedef {Object} ViewMessage
 * @property {"view"} type
 * @property {("color"|"depth"|"topdown")} [view]
 * @property {Array<("tags"|"detections"|"grid")>} [layers]
 */

/**
 * Hold still at the waypoint before it for `seconds` (added to its dwell).
 * @typedef {Object} WaitStepRequest
 * @property {"wait"} kind
 * @property {number} seconds seconds to wait (above 0, at most 3600)
 */

/**
 * @typedef {Object} WaypointInfo
 * @property {Array<number>} joints_rad
 * @property {("grasp"|"release")} gripper
 * @property {number} [dwell_s]
 * @property {(number|null)} [moving_time_s]
 * @property {(Array<number>|null)} [gripper_position_m] the gripper point at these joints (FK), world frame: project it through the calibration to draw the path
 */

/**
 * A waypoint as sent in a program edit: joints (rad, joint_names order), gripper, dwell, move time.
 * @typedef {Object} WaypointRequest
 * @property {Array<number>} joints_rad
 * @property {("grasp"|"release")} gripper
 * @property {number} [dwell_s] seconds to hold still at the waypoint
 * @property {(number|null)} [moving_time_s]
 * @property {(Array<number>|null)} [gripper_position_m] read-only (computed from joints_rad): accepted so a waypoint read can be sent back, ignored
 */

/**
 * A waypoint in a step tree ('kind' may be left out: an item without it is a waypoint).
 * @typedef {Object} WaypointStepRequest
 * @property {Array<number>} joints_rad
 * @property {("grasp"|"release")} gripper
 * @property {number} [dwell_s] seconds to hold still at the waypoint
 * @property {(number|null)} [moving_time_s]
 * @property {(Array<number>|null)} [gripper_position_m] read-only (computed from joints_rad): accepted so a waypoint read can be sent back, ignored
 * @property {"waypoint"} [kind]
 */

/**
 * The workcell's geometry (config/workcells/<name>.yaml), sent once in the hello.
 * @typedef {Object} WorkcellInfo
 * @property {string} name
 * @property {BoardInfo} board
 * @property {BoardTagsInfo} board_tags
 * @property {Object<string, *>} block_edges_m block size (large, small) -> cube edge, metres
 * @property {Object<string, *>} places_m sort_by_tag place -> [x, y], metres
 * @property {Array<number>} feeder_spot_m to_the_sky feed spot [x, y], metres
 * @property {BinInfo} bin
 */
