//! Storeys and stairs: which room a point is in, the levels of a layout, a door's
//! level, and the flights of stairs worked out from the layout and checked against the
//! rules a scene must follow.

use coherent_core::geometry::{DoorGeom, Layout, RoomGeom};

use super::error::{LayoutError, err};

/// Steepest flight a scene may have, rise over run (about 37 degrees; the legged robot
/// climbs up to 45).
pub const MAX_FLIGHT_SLOPE: f32 = 0.75;
/// Narrowest flight: the quadrotor (0.6 m) and the legged robot (0.6 m) pass with room.
pub const MIN_FLIGHT_WIDTH: f32 = 1.0;
/// A point is on a storey whose floor is at most this far (m) above it: a robot's body
/// or a thing's underside stands a little above its floor.
const LEVEL_SLACK: f32 = 0.05;
/// Lengths (m) of a flight's check closer than this are the same: a millimetre.
const EPS: f32 = 1e-3;

/// The room whose footprint holds `p` on the storey `p` is on: among the rooms whose
/// footprint holds `(x, z)`, the one with the highest level at most `LEVEL_SLACK` above
/// `p`'s height (the first in file order on a tie).
pub fn room_at(layout: &Layout, p: [f32; 3]) -> Option<&RoomGeom> {
    let mut best: Option<&RoomGeom> = None;
    for r in &layout.rooms {
        let inside = p[0] >= r.min[0] && p[0] <= r.max[0] && p[2] >= r.min[1] && p[2] <= r.max[1];
        if inside && r.level <= p[1] + LEVEL_SLACK && best.is_none_or(|b| r.level > b.level) {
            best = Some(r);
        }
    }
    best
}

/// The storeys of a layout: the distinct room levels, lowest first.
pub fn levels(layout: &Layout) -> Vec<f32> {
    let mut out: Vec<f32> = Vec::new();
    for r in &layout.rooms {
        if !out.contains(&r.level) {
            out.push(r.level);
        }
    }
    out.sort_by(f32::total_cmp);
    out
}

/// Level of a door: the level of its rooms.
pub fn door_level(layout: &Layout, d: &DoorGeom) -> f32 {
    layout
        .rooms
        .iter()
        .find(|r| r.id == d.rooms[0])
        .map_or(0.0, |r| r.level)
}

/// A flight of stairs worked out from its [`StairsGeom`](coherent_core::geometry::StairsGeom): a straight run up from the
/// lower room's level at `foot` to the upper room's level at `head`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Flight {
    pub id: i64,
    pub rooms: [i64; 2],
    /// Floor heights at the foot and at the head.
    pub lower: f32,
    pub upper: f32,
    pub foot: [f32; 2],
    pub head: [f32; 2],
    /// Unit direction of the run on the floor plan, from foot to head.
    pub dir: [f32; 2],
    /// Horizontal length of the run.
    pub run: f32,
    pub width: f32,
}

impl Flight {
    /// Whether the run goes along x (the flight is `width` wide along z).
    pub fn along_x(&self) -> bool {
        self.dir[0] != 0.0
    }

    /// Footprint `[x0, z0, x1, z1]`.
    pub fn rect(&self) -> [f32; 4] {
        let (w, l) = (self.width / 2.0, [self.dir[1].abs(), self.dir[0].abs()]);
        [
            self.foot[0].min(self.head[0]) - l[0] * w,
            self.foot[1].min(self.head[1]) - l[1] * w,
            self.foot[0].max(self.head[0]) + l[0] * w,
            self.foot[1].max(self.head[1]) + l[1] * w,
        ]
    }

    /// The point `along` metres from the foot towards the head (negative: before the
    /// foot) on the flight's middle line, at height `y`.
    pub fn at(&self, along: f32, y: f32) -> [f32; 3] {
        [
            self.foot[0] + self.dir[0] * along,
            y,
            self.foot[1] + self.dir[1] * along,
        ]
    }

    /// Height of the walking surface `along` metres from the foot.
    pub fn surface(&self, along: f32) -> f32 {
        self.lower + (self.upper - self.lower) * (along / self.run).clamp(0.0, 1.0)
    }
}

/// Every flight of the layout, checked against the rules a scene must follow (see
/// `docs/physics.md`, "Storeys and stairs"); the first broken rule, with numbers.
pub fn flights(layout: &Layout) -> Result<Vec<Flight>, LayoutError> {
    let room = |id: i64, what: &str, s: i64| {
        layout.rooms.iter().find(|r| r.id == id).ok_or_else(|| {
            LayoutError(format!(
                "stairs {s}: its {what} room {id} has no entry in rooms"
            ))
        })
    };
    for d in &layout.doors {
        let levels: Vec<f32> = d
            .rooms
            .iter()
            .filter_map(|&id| layout.rooms.iter().find(|r| r.id == id))
            .map(|r| r.level)
            .collect();
        if levels.len() == 2 && levels[0] != levels[1] {
            return err(format!(
                "door {}: its rooms are on levels {:.2} m and {:.2} m; a door joins rooms of one level (stairs join levels)",
                d.id, levels[0], levels[1]
            ));
        }
    }
    let mut out = Vec::new();
    for s in &layout.stairs {
        let lo = room(s.rooms[0], "lower", s.id)?;
        let hi = room(s.rooms[1], "upper", s.id)?;
        let rise = hi.level - lo.level;
        if rise < layout.wall_height {
            return err(format!(
                "stairs {}: the upper room is {rise:.2} m above the lower one; storeys must be at least the wall height ({:.2} m) apart",
                s.id, layout.wall_height
            ));
        }
        let (dx, dz) = (s.head[0] - s.foot[0], s.head[1] - s.foot[1]);
        if dx.abs() > EPS && dz.abs() > EPS {
            return err(format!(
                "stairs {}: foot ({:.2}, {:.2}) and head ({:.2}, {:.2}) are not on a line along x or z",
                s.id, s.foot[0], s.foot[1], s.head[0], s.head[1]
            ));
        }
        let run = dx.abs().max(dz.abs());
        if run < EPS || rise / run > MAX_FLIGHT_SLOPE {
            return err(format!(
                "stairs {}: it rises {rise:.2} m over a run of {run:.2} m; the steepest flight rises {MAX_FLIGHT_SLOPE} m per metre (a run of at least {:.2} m)",
                s.id,
                rise / MAX_FLIGHT_SLOPE
            ));
        }
        if s.width < MIN_FLIGHT_WIDTH {
            return err(format!(
                "stairs {}: {:.2} m wide; a flight is at least {MIN_FLIGHT_WIDTH} m wide",
                s.id, s.width
            ));
        }
        let dir = if dx.abs() > dz.abs() {
            [dx.signum(), 0.0]
        } else {
            [0.0, dz.signum()]
        };
        let f = Flight {
            id: s.id,
            rooms: s.rooms,
            lower: lo.level,
            upper: hi.level,
            foot: s.foot,
            head: s.head,
            dir,
            run,
            width: s.width,
        };
        let r = f.rect();
        let eps = EPS;
        if r[0] < lo.min[0] - eps
            || r[1] < lo.min[1] - eps
            || r[2] > lo.max[0] + eps
            || r[3] > lo.max[1] + eps
        {
            return err(format!(
                "stairs {}: the flight [{:.2}, {:.2}] x [{:.2}, {:.2}] is not inside its lower room's footprint",
                s.id, r[0], r[2], r[1], r[3]
            ));
        }
        // The head lies on the upper room's wall, the run pointing into the room.
        let on_wall = if f.along_x() {
            let x = if dir[0] > 0.0 { hi.min[0] } else { hi.max[0] };
            (s.head[0] - x).abs() < eps && r[1] >= hi.min[1] - eps && r[3] <= hi.max[1] + eps
        } else {
            let z = if dir[1] > 0.0 { hi.min[1] } else { hi.max[1] };
            (s.head[1] - z).abs() < eps && r[0] >= hi.min[0] - eps && r[2] <= hi.max[0] + eps
        };
        if !on_wall {
            return err(format!(
                "stairs {}: the head ({:.2}, {:.2}) is not on the wall of the upper room through which the run enters it (the whole width on that wall)",
                s.id, s.head[0], s.head[1]
            ));
        }
        // Nothing above the flight: no room of a higher storey over it.
        if let Some(over) = layout.rooms.iter().find(|o| {
            o.level > lo.level
                && o.min[0] < r[2] - eps
                && o.max[0] > r[0] + eps
                && o.min[1] < r[3] - eps
                && o.max[1] > r[1] + eps
        }) {
            return err(format!(
                "stairs {}: room {} (level {:.2} m) is over the flight; the stairwell must stay open",
                s.id, over.id, over.level
            ));
        }
        out.push(f);
    }
    Ok(out)
}
