//! Paths for the legged robot: A* on an occupancy grid of one storey's floor plan,
//! built from the colliders at the robot's height above that storey's floor (closed
//! door panels included), inflated by the robot's half width, then shortened by line of
//! sight. Storeys are joined by flights of stairs ([`crate::layout::Flight`]); the world
//! chains per-storey routes through them.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use rapier3d::prelude::*;

use crate::layout::{self, Flight, Layout};
use crate::world::Tolerances;

pub(crate) struct Grid {
    x0: f32,
    z0: f32,
    nx: usize,
    nz: usize,
    blocked: Vec<bool>,
    /// Side of a cell (`Tolerances::path_cell`).
    cell: f32,
    /// How far into blocked cells a route may go to leave the margin it starts in
    /// (`Tolerances::path_escape_cost`).
    escape_cost: u32,
}

impl Grid {
    /// The grid of the storey whose floor is at `level`, from the layout's rooms and
    /// doors, its `flights`, and the `colliders` (those of the legged robot's body `dog`
    /// left out), with the cell size and margins of `tol`.
    pub fn new(
        layout: &Layout,
        flights: &[Flight],
        colliders: &ColliderSet,
        dog: RigidBodyHandle,
        level: f32,
        tol: &Tolerances,
    ) -> Grid {
        let (mut x0, mut z0, mut x1, mut z1) = (f32::MAX, f32::MAX, f32::MIN, f32::MIN);
        for r in &layout.rooms {
            x0 = x0.min(r.min[0]);
            z0 = z0.min(r.min[1]);
            x1 = x1.max(r.max[0]);
            z1 = z1.max(r.max[1]);
        }
        let cell = tol.path_cell;
        let nx = ((x1 - x0) / cell).ceil() as usize + 1;
        let nz = ((z1 - z0) / cell).ceil() as usize + 1;
        let mut g = Grid {
            x0,
            z0,
            nx,
            nz,
            blocked: vec![true; nx * nz],
            cell,
            escape_cost: tol.path_escape_cost,
        };
        let h = layout.specs.dog_half;
        let inflate = h[0].max(h[2]) + tol.path_margin;
        // Free inside the storey's rooms, minus a margin along the outer footprint.
        for r in layout.rooms.iter().filter(|r| r.level == level) {
            g.mark(
                r.min[0] + inflate,
                r.min[1] + inflate,
                r.max[0] - inflate,
                r.max[1] - inflate,
                false,
            );
        }
        // Door openings are passable (their panels, when closed, block below), and so is
        // the opening where a flight arrives on this storey: a box across the opening
        // (its middle, its width, whether it runs along x), `path_opening_depth` beyond
        // the margin into each side.
        let doors = layout
            .doors
            .iter()
            .filter(|d| layout::door_level(layout, d) == level)
            .map(|d| (d.center, d.width, d.along_x));
        let heads = flights
            .iter()
            .filter(|f| f.upper == level)
            .map(|f| (f.head, f.width, !f.along_x()));
        for (c, width, along_x) in doors.chain(heads) {
            let (half, deep) = (width / 2.0 - inflate, inflate + tol.path_opening_depth);
            let (ax, az) = if along_x { (half, deep) } else { (deep, half) };
            g.mark(c[0] - ax, c[1] - az, c[0] + ax, c[1] + az, false);
        }
        for (_, c) in colliders.iter() {
            if c.collision_groups().memberships == Group::NONE || c.parent() == Some(dog) {
                continue;
            }
            let a = c.compute_aabb();
            // Only what stands at the robot's height; floors are below it.
            if a.maxs.y < level + tol.path_min_height || a.mins.y > level + tol.path_max_height {
                continue;
            }
            g.mark(
                a.mins.x - inflate,
                a.mins.z - inflate,
                a.maxs.x + inflate,
                a.maxs.z + inflate,
                true,
            );
        }
        g
    }

    fn mark(&mut self, x0: f32, z0: f32, x1: f32, z1: f32, blocked: bool) {
        let (i0, k0) = self.cell_of(x0, z0);
        let (i1, k1) = self.cell_of(x1, z1);
        for k in k0..=k1 {
            for i in i0..=i1 {
                self.blocked[k * self.nx + i] = blocked;
            }
        }
    }

    fn cell_of(&self, x: f32, z: f32) -> (usize, usize) {
        let i = ((x - self.x0) / self.cell)
            .round()
            .clamp(0.0, (self.nx - 1) as f32) as usize;
        let k = ((z - self.z0) / self.cell)
            .round()
            .clamp(0.0, (self.nz - 1) as f32) as usize;
        (i, k)
    }

    fn centre(&self, i: usize, k: usize) -> (f32, f32) {
        (
            self.x0 + i as f32 * self.cell,
            self.z0 + k as f32 * self.cell,
        )
    }

    pub fn free(&self, p: Vector) -> bool {
        let (i, k) = self.cell_of(p.x, p.z);
        !self.blocked[k * self.nx + i]
    }

    fn line_free(&self, a: Vector, b: Vector) -> bool {
        // Sampled every half cell: no cell is stepped over.
        let n = ((b - a).length() / (self.cell * 0.5)).ceil() as usize;
        (0..=n).all(|s| {
            let p = a + (b - a) * (s as f32 / n.max(1) as f32);
            self.free(p)
        })
    }

    /// Waypoints from `start` to `goal` (start first), or `None` when no path exists.
    pub fn route(&self, start: Vector, goal: Vector) -> Option<Vec<Vector>> {
        let (si, sk) = self.cell_of(start.x, start.z);
        let (gi, gk) = self.cell_of(goal.x, goal.z);
        if self.blocked[gk * self.nx + gi] {
            return None;
        }
        let idx = |i: usize, k: usize| k * self.nx + i;
        let h = |i: usize, k: usize| {
            let (dx, dz) = ((i as i64 - gi as i64).abs(), (k as i64 - gk as i64).abs());
            (dx.max(dz) * 10 + dx.min(dz) * 4) as u32
        };
        let mut cost = vec![u32::MAX; self.nx * self.nz];
        let mut prev = vec![usize::MAX; self.nx * self.nz];
        let mut open = BinaryHeap::new();
        cost[idx(si, sk)] = 0;
        open.push(Reverse((h(si, sk), idx(si, sk))));
        // Leaving the start cell is allowed even when the robot stands in a margin.
        while let Some(Reverse((_, cur))) = open.pop() {
            if cur == idx(gi, gk) {
                break;
            }
            let (ci, ck) = (cur % self.nx, cur / self.nx);
            for (di, dk, c) in [
                (1i64, 0i64, 10u32),
                (-1, 0, 10),
                (0, 1, 10),
                (0, -1, 10),
                (1, 1, 14),
                (1, -1, 14),
                (-1, 1, 14),
                (-1, -1, 14),
            ] {
                let (ni, nk) = (ci as i64 + di, ck as i64 + dk);
                if ni < 0 || nk < 0 || ni >= self.nx as i64 || nk >= self.nz as i64 {
                    continue;
                }
                let (ni, nk) = (ni as usize, nk as usize);
                let j = idx(ni, nk);
                // Blocked cells only while escaping the margin the robot starts in.
                if self.blocked[j] && (!self.blocked[cur] || cost[cur] > self.escape_cost) {
                    continue;
                }
                let nc = cost[cur].saturating_add(c);
                if nc < cost[j] {
                    cost[j] = nc;
                    prev[j] = cur;
                    open.push(Reverse((nc + h(ni, nk), j)));
                }
            }
        }
        if cost[idx(gi, gk)] == u32::MAX {
            return None;
        }
        let mut cells = vec![idx(gi, gk)];
        while let Some(&c) = cells.last() {
            if c == idx(si, sk) {
                break;
            }
            cells.push(prev[c]);
        }
        cells.reverse();
        let mut pts: Vec<Vector> = cells
            .iter()
            .map(|&c| {
                let (x, z) = self.centre(c % self.nx, c / self.nx);
                Vector::new(x, start.y, z)
            })
            .collect();
        pts[0] = start;
        if let Some(last) = pts.last_mut() {
            *last = Vector::new(goal.x, start.y, goal.z);
        }
        // Shortcut by line of sight.
        let mut out = vec![pts[0]];
        let mut i = 0;
        while i + 1 < pts.len() {
            let mut j = pts.len() - 1;
            while j > i + 1 && !self.line_free(pts[i], pts[j]) {
                j -= 1;
            }
            out.push(pts[j]);
            i = j;
        }
        Some(out)
    }
}
