//! The numbers the simulation works to, in one place (as Rapier's
//! `IntegrationParameters` holds its solver's): the step, the tolerances a check allows,
//! the margins and clearances motions keep, their speeds and limits, and the gains of the
//! quadrotor's controller, each with its unit and why it has its value. A [`World`] holds
//! them (`World::tolerances`) and every job reads them from there; the defaults are the
//! values all the project's results were computed with.
//!
//! What is not here: the robots' and the furniture's dimensions (the layout's
//! `RobotSpecs` and sizes, and the robot models' own in `build.rs`), the drawing's
//! measures (`render`), and the layout generator's spacing (`layout`).
//!
//! [`World`]: super::World

use std::f32::consts::FRAC_PI_4;

/// The simulation's step, tolerances, margins, speeds, limits and controller gains.
/// Lengths are in metres, times in seconds, angles in radians unless a name says
/// degrees; counts of simulation steps are at [`Tolerances::dt`] each.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tolerances {
    // The simulation.
    /// Simulation step (s): Rapier's `dt`. 60 Hz, what the quadrotor's controller was
    /// tuned for; every count of steps below is of this step.
    pub dt: f32,
    /// Longest wait (s) for loose things to come to rest once the world is built: things
    /// are placed a few millimetres above what holds them and drop into place.
    pub initial_settle: f32,
    /// Steps a wait for loose things to rest takes before they may count as resting:
    /// something let go of starts at rest, before it falls.
    pub settle_min_steps: usize,
    /// A loose thing slower than this (m/s) rests.
    pub rest_speed: f32,
    /// ... and turning slower than this (rad/s).
    pub rest_spin: f32,
    /// Lengths closer than this (m) are the same: a door or a flight on a wall's line, a
    /// piece of wall too thin to build. A millimetre: far below any size in a layout.
    pub geometry_epsilon: f32,
    /// A mobile robot's track gets a point every this far (m) on the floor plan: a smooth
    /// line in a picture at a few points a metre.
    pub track_spacing: f32,
    /// How often (steps; half a second) an action of a joint step that waits for its way
    /// or spot to clear plans again.
    pub retry_steps: usize,
    /// How close (m) what a robot brings into a joint step may come to what a robot
    /// earlier in the step brings before it holds (`contact.rs`): 10 cm, more than a
    /// step's travel at the robots' speeds.
    pub contact_clearance: f32,

    // Reading the relations back.
    /// A body's underside is read this far (m) above its lowest point: a ray from there
    /// starts above what the body rests on, and the point lies inside a container the
    /// body rests in.
    pub underside_lift: f32,
    /// The longest drop (m) under a body in which what it rests on is looked for.
    pub support_ray: f32,
    /// A point this far (m) above a thing's bottom is in the thing's room (above its
    /// floor, whatever the thing stands on).
    pub room_probe_lift: f32,
    /// The quadrotor with its motors off counts as landed when slower than this (m/s).
    pub quad_landed_speed: f32,
    /// A door or lid the rules have open must be open at least this far (degrees).
    pub open_min_degrees: f32,
    /// A door or lid the rules have closed may be open at most this far (degrees).
    pub closed_max_degrees: f32,
    /// The legged robot is CLOSE to a thing within its arm's reach and this much more (m)
    /// from its shoulder.
    pub close_margin: f32,
    /// How many holders deep (a thing on a plate in a box on a table) the legged robot
    /// looks for the furniture it walks to.
    pub anchor_depth: usize,

    // The quadrotor: its controller.
    /// Gravity (m/s²) as the controller feeds it forward (Rapier's world pulls at the
    /// same 9.81).
    pub gravity: f32,
    /// Position gain (1/s²) of the position loop.
    pub quad_kp: f32,
    /// Velocity gain (1/s) of the position loop.
    pub quad_kd: f32,
    /// Integral gain (1/s³) of the position loop: removes the offset a load or a tilted
    /// start leaves.
    pub quad_ki: f32,
    /// Largest integral of the position error (m s): no wind-up.
    pub quad_integral_limit: f32,
    /// A set point slower than this (m/s) is hovering: only then does the horizontal
    /// integral run (it would wind up on the lag behind a long flight).
    pub quad_hover_setpoint_speed: f32,
    /// Largest horizontal acceleration (m/s²) the position loop asks for: it limits the
    /// tilt.
    pub quad_max_horizontal_accel: f32,
    /// Largest vertical acceleration (m/s²), up or down.
    pub quad_max_vertical_accel: f32,
    /// Moment of inertia (kg m²) the attitude loop assumes about every axis.
    pub quad_inertia: f32,
    /// Gain (1/s²) on the tilt between the body's up and the wanted thrust.
    pub quad_tilt_gain: f32,
    /// Gain (1/s²) on the yaw away from zero.
    pub quad_yaw_gain: f32,
    /// Gain (1/s) on the turn rate (damping).
    pub quad_rate_gain: f32,
    /// What rests in the basket counts as its load down to this far (m) below its inner
    /// floor ...
    pub basket_load_below: f32,
    /// ... and up to this high (m) above its middle.
    pub basket_load_height: f32,

    // The quadrotor: flights and landing.
    /// The craft starts this far (m) above where the layout puts it, not in what it
    /// stands on.
    pub quad_start_lift: f32,
    /// The set point has reached a waypoint within this (m).
    pub quad_waypoint_epsilon: f32,
    /// Longest hover at the end of a flight (steps; ten seconds) before it fails.
    pub quad_hover_max_steps: usize,
    /// A hover is over only after this many steps (the craft still swings after a stop).
    pub quad_hover_min_steps: usize,
    /// ... and once the craft is within this (m) of the end ...
    pub quad_hover_radius: f32,
    /// ... and slower than this (m/s).
    pub quad_hover_speed: f32,
    /// A fixed collider of no node whose top is higher than this (m) is a wall (or a
    /// flight) to a flying craft: the ground under the things set aside is not.
    pub quad_wall_min_top: f32,
    /// Free room (m) around the craft's frame a landing spot needs: it must not brush a
    /// wall or an arm on arrival.
    pub quad_landing_margin: f32,
    /// Half height (m) of the box that must be free over a landing spot ...
    pub quad_landing_probe_half_height: f32,
    /// ... whose middle is this far (m) above the spot.
    pub quad_landing_probe_lift: f32,
    /// Spacing (m) of the landing spots tried on a surface.
    pub quad_landing_grid: f32,
    /// A landing spot is this far (m) above the surface.
    pub quad_landing_lift: f32,
    /// On a floor, landing spots keep this much more (m) off the walls: the craft
    /// overshoots a little on arrival.
    pub quad_floor_wall_gap: f32,
    /// A landing spot next to a fixed arm is this far (m) from its base: close, with room
    /// for the base.
    pub quad_arm_distance: f32,
    /// Beyond a door's width and the craft's half width, the craft leaves the wall this
    /// much further (m) before it turns to the doorway (an open panel stands out that far).
    pub quad_door_clearance: f32,
    /// ... and at least this far (m) in all.
    pub quad_door_min_clear: f32,
    /// The turning points of a flight stay this far (m) inside their room (its middle
    /// line when it is narrower): a hallway is crossed, not flown out of.
    pub quad_room_margin: f32,
    /// Between storeys the craft climbs (or descends) this far (m) up the flight from its
    /// foot, where nothing is above it ...
    pub quad_stairs_climb_at: f32,
    /// ... and flies on to this far (m) past the flight's head, into the upper room.
    pub quad_stairs_past_head: f32,
    /// A take-off rises this far (m).
    pub quad_takeoff_height: f32,
    /// Flying to a surface, the craft hovers this far (m) above its top.
    pub quad_hover_height: f32,
    /// To land it flies over the spot at least this high (m) above it ...
    pub quad_approach_height: f32,
    /// ... down to this high (m), where the slow descent starts.
    pub quad_descent_start: f32,
    /// Speed (m/s) of the descent until the basket touches.
    pub quad_descent_speed: f32,
    /// Longest descent (steps; ten seconds).
    pub quad_descent_max_steps: usize,
    /// Longest wait (s) for the craft to come to rest once the motors are off.
    pub quad_landing_settle: f32,

    // The legged robot.
    /// The body walks this far (m) above the floor or flight under it (the stairs
    /// controller's offset too).
    pub dog_floor_gap: f32,
    /// The floor controller's offset (m): the gap it keeps to what it slides along.
    pub dog_skin: f32,
    /// Steepest slope (rad) the stairs controller climbs: 45 degrees, steeper than any
    /// flight (`MAX_FLIGHT_SLOPE`).
    pub dog_stairs_max_slope: f32,
    /// Going down a flight the body keeps to the slope within this (m).
    pub dog_stairs_snap: f32,
    /// The robot lines up with a flight this far (m) before its foot and past its head.
    pub dog_flight_approach: f32,
    /// Off a flight, the body must be within this (m) of the height it walks at on the
    /// floor there.
    pub dog_off_stairs_tolerance: f32,
    /// Each waypoint of a walk gets this many times the steps its straight distance takes
    /// ...
    pub dog_walk_budget_factor: f32,
    /// ... and this many more.
    pub dog_walk_budget_steps: usize,
    /// Closer than this (m) to a waypoint, the walk to it is over ...
    pub dog_waypoint_reached: f32,
    /// ... and it must end within this (m) of it.
    pub dog_waypoint_tolerance: f32,
    /// A step that moves the robot less than this part of the way it wanted to go is
    /// stuck ...
    pub dog_stuck_fraction: f32,
    /// ... and more than this many stuck steps in a row are blocked.
    pub dog_stuck_steps: usize,
    /// Beyond its half width, the robot stands this far (m) from what it works on.
    pub dog_service_gap: f32,
    /// Where along a side of what it works on the robot may stand, as parts of that
    /// side's half length, in the order tried.
    pub dog_service_offsets: [f32; 5],
    /// How much further out (m) from a side a spot may be when the first is not free (a
    /// wall beside a door, the grid's cells).
    pub dog_service_steps_out: [f32; 4],
    /// Entering a room, the robot aims this far (m) past the door or the flight's end.
    pub dog_room_entry: f32,
    /// Rings of spots tried around that aim, for a free one ...
    pub dog_room_search_rings: usize,
    /// ... this far (m) apart ...
    pub dog_room_search_spacing: f32,
    /// ... and spots on each ring.
    pub dog_room_search_directions: usize,
    /// The hand may reach this much (m) above the robot's highest reach (a target at the
    /// height limit is still reached).
    pub dog_height_margin: f32,

    // The legged robot's paths (`path.rs`).
    /// Side (m) of a cell of the occupancy grid.
    pub path_cell: f32,
    /// Obstacles grow by the robot's half width and this (m).
    pub path_margin: f32,
    /// A door's opening is free this far (m) beyond the margin into each room.
    pub path_opening_depth: f32,
    /// Colliders from this high (m) above a storey's floor ...
    pub path_min_height: f32,
    /// ... up to this high (m) block its grid (higher ones are over the robot).
    pub path_max_height: f32,
    /// A path may cross blocked cells only to leave the margin it starts in, within
    /// this cost (straight cells cost 10 each, diagonal ones 14).
    pub path_escape_cost: u32,

    // The arms.
    /// Damping of Rapier's inverse kinematics.
    pub ik_damping: f32,
    /// Its most iterations.
    pub ik_max_iters: usize,
    /// Its tolerance on the hand's position (m).
    pub ik_epsilon_linear: f32,
    /// Its tolerance on the hand's orientation (rad; the orientation is not constrained).
    pub ik_epsilon_angular: f32,
    /// The (shoulder, elbow) seeds the solver starts from besides the arm's pose, with
    /// the yaw towards the target: they avoid its local minima.
    pub ik_seeds: [[f32; 2]; 2],
    /// A solution within the joint limits that misses the target by more (m) is out of
    /// reach.
    pub ik_miss: f32,
    /// Fastest joint speed (rad/s) of an arm's move ...
    pub arm_joint_speed: f32,
    /// ... which takes at least this many steps.
    pub arm_min_steps: usize,
    /// After a move the hand must be within this (m) of its target.
    pub hand_tolerance: f32,
    /// A grasp reaches this far (m) above the middle of the thing's top.
    pub grasp_above: f32,
    /// A put lets go with the thing's underside this far (m) above its spot.
    pub put_drop: f32,
    /// Spacing (m) of the spots tried on a surface or in a container.
    pub put_grid: f32,
    /// A spot is this far (m) above the surface.
    pub put_lift: f32,
    /// The box that must be free at a spot is the thing's, this much (m) smaller on every
    /// side ...
    pub put_probe_shrink: f32,
    /// ... and this far (m) up.
    pub put_probe_lift: f32,
    /// Spots keep this far (m) inside the surface's edges.
    pub put_edge_margin: f32,
    /// A thing still fits on or in a holder up to this much (m) too narrow for it within
    /// the edge margins.
    pub put_fit_tolerance: f32,
    /// A spot is within reach this much (m) inside the arm's reach ...
    pub put_reach_margin: f32,
    /// ... and this much (m) beyond its closest reach (the folded arm).
    pub put_min_reach_margin: f32,
    /// Longest wait (s) for a thing let go of to rest ...
    pub release_settle: f32,
    /// ... and for everything to rest once the arm is folded back.
    pub home_settle: f32,
    /// A lid must be open at least this far (rad) to put something into its container.
    pub lid_open_min: f32,
    /// Steps a door or lid takes to turn.
    pub hinge_steps: usize,
}

impl Default for Tolerances {
    fn default() -> Tolerances {
        Tolerances {
            dt: 1.0 / 60.0,
            initial_settle: 1.0,
            settle_min_steps: 10,
            rest_speed: 0.01,
            rest_spin: 0.05,
            geometry_epsilon: 1e-3,
            track_spacing: 0.2,
            retry_steps: 30,
            contact_clearance: 0.1,

            underside_lift: 0.01,
            support_ray: 3.0,
            room_probe_lift: 0.05,
            quad_landed_speed: 0.05,
            open_min_degrees: 60.0,
            closed_max_degrees: 2.0,
            close_margin: 0.01,
            anchor_depth: 6,

            gravity: 9.81,
            quad_kp: 3.0,
            quad_kd: 3.5,
            quad_ki: 1.5,
            quad_integral_limit: 0.5,
            quad_hover_setpoint_speed: 1e-3,
            quad_max_horizontal_accel: 2.5,
            quad_max_vertical_accel: 4.0,
            quad_inertia: 0.08,
            quad_tilt_gain: 60.0,
            quad_yaw_gain: 4.0,
            quad_rate_gain: 12.0,
            basket_load_below: 0.02,
            basket_load_height: 0.4,

            quad_start_lift: 0.003,
            quad_waypoint_epsilon: 1e-4,
            quad_hover_max_steps: 600,
            quad_hover_min_steps: 20,
            quad_hover_radius: 0.05,
            quad_hover_speed: 0.08,
            quad_wall_min_top: 0.5,
            quad_landing_margin: 0.25,
            quad_landing_probe_half_height: 0.13,
            quad_landing_probe_lift: 0.14,
            quad_landing_grid: 0.1,
            quad_landing_lift: 0.005,
            quad_floor_wall_gap: 0.45,
            quad_arm_distance: 0.55,
            quad_door_clearance: 0.2,
            quad_door_min_clear: 1.6,
            quad_room_margin: 0.8,
            quad_stairs_climb_at: 0.6,
            quad_stairs_past_head: 1.6,
            quad_takeoff_height: 0.7,
            quad_hover_height: 0.7,
            quad_approach_height: 0.5,
            quad_descent_start: 0.25,
            quad_descent_speed: 0.3,
            quad_descent_max_steps: 600,
            quad_landing_settle: 1.5,

            dog_floor_gap: 0.02,
            dog_skin: 0.01,
            dog_stairs_max_slope: FRAC_PI_4,
            dog_stairs_snap: 0.2,
            dog_flight_approach: 0.55,
            dog_off_stairs_tolerance: 0.03,
            dog_walk_budget_factor: 3.0,
            dog_walk_budget_steps: 120,
            dog_waypoint_reached: 0.01,
            dog_waypoint_tolerance: 0.05,
            dog_stuck_fraction: 0.2,
            dog_stuck_steps: 30,
            dog_service_gap: 0.12,
            dog_service_offsets: [0.0, -0.6, 0.6, -0.3, 0.3],
            dog_service_steps_out: [0.0, 0.1, 0.2, 0.3],
            dog_room_entry: 1.0,
            dog_room_search_rings: 20,
            dog_room_search_spacing: 0.15,
            dog_room_search_directions: 16,
            dog_height_margin: 0.01,

            path_cell: 0.1,
            path_margin: 0.03,
            path_opening_depth: 0.15,
            path_min_height: 0.03,
            path_max_height: 0.75,
            path_escape_cost: 60,

            ik_damping: 0.05,
            ik_max_iters: 80,
            ik_epsilon_linear: 1e-3,
            ik_epsilon_angular: 1.0,
            ik_seeds: [[-0.6, 1.4], [0.2, 0.6]],
            ik_miss: 0.02,
            arm_joint_speed: 1.5,
            arm_min_steps: 10,
            hand_tolerance: 0.03,
            grasp_above: 0.01,
            put_drop: 0.01,
            put_grid: 0.04,
            put_lift: 0.003,
            put_probe_shrink: 0.005,
            put_probe_lift: 0.004,
            put_edge_margin: 0.01,
            put_fit_tolerance: 0.005,
            put_reach_margin: 0.03,
            put_min_reach_margin: 0.05,
            release_settle: 0.5,
            home_settle: 1.0,
            lid_open_min: 1.0,
            hinge_steps: 60,
        }
    }
}
