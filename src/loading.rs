//! Prescribed motion and loads: the rigid walls and how they travel, the prescribed
//! displacements, the edge loads, and the amplitudes that scale them in time.
//!
//! The one owner of "where is a wall at time t" and "what is a prescribed dof at time t": the
//! solver (predictor, residual), the contact (wall planes), the jam test, the external work
//! and the output all ask [`Loading`]. A leaf module: it knows no physics.
//!
//! A wall's inward travel d(t) (mm) moves it from its initial `position`: a left or bottom
//! wall sits at `position + d(t)`, a right or top wall at `position − d(t)`. It is either
//! - `velocity · t` (a constant speed, mm/s, the paper's 10 mm/s), or
//! - `travel · f(t)` with an amplitude f, exactly as a prescribed displacement `u = value ·
//!   f(t)`: `ramp` (the default) moves the wall by `travel` over the run at constant speed,
//!   a table shapes the motion (press, hold, release).

/// Time variation of a prescribed value: the value is multiplied by `at(t, t_end)`.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Amplitude {
    /// 0 at t = 0, 1 at t = t_end, linear in between (held at 1 after t_end).
    #[default]
    Ramp,
    /// 1 at all times.
    Constant,
    /// Piecewise linear through `[t, f]` points (times strictly increasing), constant outside.
    Table(Vec<[f64; 2]>),
}

impl Amplitude {
    /// Amplitude factor at time `t` of an analysis that ends at `t_end`.
    pub fn at(&self, t: f64, t_end: f64) -> f64 {
        match self {
            Amplitude::Ramp => {
                if t_end > 0.0 {
                    (t / t_end).clamp(0.0, 1.0)
                } else {
                    1.0
                }
            }
            Amplitude::Constant => 1.0,
            Amplitude::Table(pts) => {
                let (Some(first), Some(last)) = (pts.first(), pts.last()) else {
                    return 0.0;
                };
                if t <= first[0] {
                    return first[1];
                }
                if t >= last[0] {
                    return last[1];
                }
                for w in pts.windows(2) {
                    let (a, b) = (w[0], w[1]);
                    if t <= b[0] {
                        let dt = b[0] - a[0];
                        if dt <= 0.0 {
                            return b[1];
                        }
                        return a[1] + (b[1] - a[1]) * (t - a[0]) / dt;
                    }
                }
                last[1]
            }
        }
    }
}

/// Which side of the die a rigid wall closes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WallSide {
    Left,
    Right,
    Bottom,
    Top,
}

impl WallSide {
    /// Position of the side in the history's wall columns: left 0, right 1, bottom 2, top 3.
    pub fn index(self) -> usize {
        match self {
            WallSide::Left => 0,
            WallSide::Right => 1,
            WallSide::Bottom => 2,
            WallSide::Top => 3,
        }
    }

    /// Unit normal pointing into the die (towards the particles).
    pub fn inward_normal(self) -> [f64; 2] {
        match self {
            WallSide::Left => [1.0, 0.0],
            WallSide::Right => [-1.0, 0.0],
            WallSide::Bottom => [0.0, 1.0],
            WallSide::Top => [0.0, -1.0],
        }
    }
}

/// How a wall travels inward from its initial position (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub enum WallTravel {
    /// d(t) = velocity · t (mm/s, positive inward; 0: a fixed wall).
    Velocity(f64),
    /// d(t) = travel · f(t) with amplitude `amplitude` of [`Loading::amplitudes`] (mm).
    Amplitude { travel: f64, amplitude: usize },
}

/// A rigid straight wall of the die.
#[derive(Clone, Debug, PartialEq)]
pub struct WallMotion {
    pub side: WallSide,
    /// x of a left/right wall, y of a bottom/top wall at t = 0 (mm).
    pub position: f64,
    pub travel: WallTravel,
}

/// A prescribed displacement component: `u[dof] = value · amplitude(t)`.
#[derive(Clone, Debug, PartialEq)]
pub struct PrescribedDof {
    pub dof: usize,
    pub value: f64,
    pub amplitude: usize,
}

/// Kind and value of a load on an edge set.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LoadKind {
    /// Dead traction per reference length `[tx, ty]`, MPa.
    Traction([f64; 2]),
    /// Follower pressure normal to the current edge, MPa (positive pushes into the body).
    Pressure(f64),
    /// Total force `[Fx, Fy]` (N per unit thickness) spread uniformly over the set's
    /// reference length.
    Force([f64; 2]),
}

/// A distributed load on a list of boundary edges (global node indices, body on the left).
#[derive(Clone, Debug, PartialEq)]
pub struct EdgeLoad {
    pub edges: Vec<[usize; 2]>,
    pub kind: LoadKind,
    pub amplitude: usize,
    /// Reference length of the edge set (mm), used by `LoadKind::Force`.
    pub length0: f64,
}

/// Everything prescribed in time: walls, displacements, loads and their amplitudes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Loading {
    pub walls: Vec<WallMotion>,
    /// Sorted by dof, one entry per dof.
    pub prescribed: Vec<PrescribedDof>,
    pub loads: Vec<EdgeLoad>,
    pub amplitudes: Vec<Amplitude>,
    /// End time of the run (s): amplitudes "ramp" go from 0 to 1 over [0, t_end].
    pub t_end: f64,
}

impl Loading {
    /// Amplitude factor of amplitude `i` at time `t`.
    pub fn amplitude(&self, i: usize, t: f64) -> f64 {
        self.amplitudes[i].at(t, self.t_end)
    }

    /// The value of prescribed dof `p` at time `t` (mm).
    pub fn prescribed_value(&self, p: &PrescribedDof, t: f64) -> f64 {
        p.value * self.amplitude(p.amplitude, t)
    }

    /// Set every prescribed dof of `u` (all dofs) to its value at time `t`.
    pub fn apply_prescribed(&self, u: &mut [f64], t: f64) {
        for p in &self.prescribed {
            u[p.dof] = self.prescribed_value(p, t);
        }
    }

    /// Inward travel d(t) of wall `w` since t = 0 (mm).
    pub fn wall_travel(&self, w: usize, t: f64) -> f64 {
        match self.walls[w].travel {
            WallTravel::Velocity(v) => v * t,
            WallTravel::Amplitude { travel, amplitude } => travel * self.amplitude(amplitude, t),
        }
    }

    /// Position of wall `w` at time t (x of left/right, y of bottom/top, mm).
    pub fn wall_position(&self, w: usize, t: f64) -> f64 {
        let wall = &self.walls[w];
        match wall.side {
            WallSide::Left | WallSide::Bottom => wall.position + self.wall_travel(w, t),
            WallSide::Right | WallSide::Top => wall.position - self.wall_travel(w, t),
        }
    }

    /// Wall `w` at time t as a plane: a point on it and its unit normal into the die.
    pub fn wall_plane(&self, w: usize, t: f64) -> ([f64; 2], [f64; 2]) {
        let p = self.wall_position(w, t);
        let side = self.walls[w].side;
        let point = match side {
            WallSide::Left | WallSide::Right => [p, 0.0],
            WallSide::Bottom | WallSide::Top => [0.0, p],
        };
        (point, side.inward_normal())
    }

    /// The sides (`WallSide::index`) of the pressing walls, those that move.
    pub fn pressing_sides(&self) -> Vec<usize> {
        (0..self.walls.len()).filter(|&w| self.wall_moves(w)).map(|w| self.walls[w].side.index()).collect()
    }

    /// Whether wall `w` moves at all during the run (a pressing wall).
    pub fn wall_moves(&self, w: usize) -> bool {
        match self.walls[w].travel {
            WallTravel::Velocity(v) => v != 0.0,
            WallTravel::Amplitude { travel, .. } => travel != 0.0,
        }
    }

    /// How far any wall may move during a step from `t` to `t + dt` (mm): |v| Δt for a wall at
    /// constant speed, the largest travel change over the step's amplitude interval otherwise
    /// (an amplitude is piecewise linear, so its extremes over the step are at the ends or at
    /// table points inside).
    pub fn wall_reach(&self, t: f64, dt: f64) -> f64 {
        let mut reach: f64 = 0.0;
        for (w, wall) in self.walls.iter().enumerate() {
            let r = match &wall.travel {
                WallTravel::Velocity(v) => v.abs() * dt,
                WallTravel::Amplitude { amplitude, .. } => {
                    let d0 = self.wall_travel(w, t);
                    let mut r = (self.wall_travel(w, t + dt) - d0).abs();
                    if let Amplitude::Table(pts) = &self.amplitudes[*amplitude] {
                        for p in pts.iter().filter(|p| p[0] > t && p[0] < t + dt) {
                            r = r.max((self.wall_travel(w, p[0]) - d0).abs());
                        }
                    }
                    r
                }
            };
            reach = reach.max(r);
        }
        reach
    }

    /// Index of the wall on `side`, if any.
    pub fn wall_on(&self, side: WallSide) -> Option<usize> {
        self.walls.iter().position(|w| w.side == side)
    }

    /// The die `[x_left, x_right, y_bottom, y_top]` at time t, when all four walls exist.
    pub fn die(&self, t: f64) -> Option<[f64; 4]> {
        let pos = |s: WallSide| self.wall_on(s).map(|w| self.wall_position(w, t));
        Some([pos(WallSide::Left)?, pos(WallSide::Right)?, pos(WallSide::Bottom)?, pos(WallSide::Top)?])
    }

    /// The die's area at time t (mm²), when all four walls exist: what a solid ratio divides by.
    pub fn die_area(&self, t: f64) -> Option<f64> {
        self.die(t).map(|[x0, x1, y0, y1]| (x1 - x0) * (y1 - y0))
    }

    /// Current length of wall `w` (mm): the distance between the two walls it spans, or, when
    /// those walls are missing, the extent of the points `x` (the particles' boundary nodes)
    /// across it.
    pub fn wall_length(&self, w: usize, t: f64, x: impl Iterator<Item = [f64; 2]> + Clone) -> f64 {
        let pos = |s: WallSide| self.wall_on(s).map(|q| self.wall_position(q, t));
        let extent = |c: usize| {
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for p in x.clone() {
                lo = lo.min(p[c]);
                hi = hi.max(p[c]);
            }
            hi - lo
        };
        match self.walls[w].side {
            WallSide::Left | WallSide::Right => match (pos(WallSide::Bottom), pos(WallSide::Top)) {
                (Some(a), Some(b)) => b - a,
                _ => extent(1),
            },
            WallSide::Bottom | WallSide::Top => match (pos(WallSide::Left), pos(WallSide::Right)) {
                (Some(a), Some(b)) => b - a,
                _ => extent(0),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn die(travel: WallTravel) -> Loading {
        let wall = |side, position| WallMotion { side, position, travel: WallTravel::Velocity(0.0) };
        let mut l = Loading {
            walls: vec![wall(WallSide::Left, 0.0), wall(WallSide::Right, 100.0), wall(WallSide::Bottom, 0.0), wall(WallSide::Top, 80.0)],
            amplitudes: vec![Amplitude::Ramp, Amplitude::Table(vec![[0.0, 0.0], [2.0, 1.0], [3.0, 1.0], [4.0, 0.5]])],
            t_end: 4.0,
            ..Default::default()
        };
        l.walls[1].travel = travel;
        l
    }

    /// A wall at constant speed is at position ∓ v t; a wall with a travel and an amplitude
    /// is where a prescribed displacement `travel · f(t)` would put it (hand values).
    #[test]
    fn wall_positions_follow_velocity_or_amplitude() {
        let l = die(WallTravel::Velocity(10.0));
        assert_eq!(l.wall_position(1, 1.5), 85.0);
        assert_eq!(l.die(1.5), Some([0.0, 85.0, 0.0, 80.0]));
        assert!(l.wall_moves(1) && !l.wall_moves(0));
        assert_eq!(l.wall_reach(1.0, 0.2), 2.0);
        // ramp: travel 20 over t_end = 4 s → 7.5 mm at 1.5 s
        let l = die(WallTravel::Amplitude { travel: 20.0, amplitude: 0 });
        assert_eq!(l.wall_position(1, 1.5), 92.5);
        assert_eq!(l.wall_position(1, 6.0), 80.0, "held after t_end");
        // table: press to 20 mm in 2 s, hold, release to 10 mm at 4 s
        let l = die(WallTravel::Amplitude { travel: 20.0, amplitude: 1 });
        for (t, x) in [(0.0, 100.0), (1.0, 90.0), (2.5, 80.0), (3.5, 85.0), (4.0, 90.0)] {
            assert!((l.wall_position(1, t) - x).abs() < 1e-12, "t = {t}: {}", l.wall_position(1, t));
        }
        // the reach over a step that contains the table's peak sees the peak, not the ends
        // (1.5 → 3.5 s: from 15 mm up to 20 and back to 15)
        assert!((l.wall_reach(1.5, 2.0) - 5.0).abs() < 1e-12, "{}", l.wall_reach(1.5, 2.0));
    }

    /// The wall lengths are the distances between the spanning walls; without them the extent
    /// of the points.
    #[test]
    fn wall_lengths() {
        let l = die(WallTravel::Velocity(10.0));
        let pts = [[1.0, 2.0], [5.0, 9.0]];
        assert_eq!(l.wall_length(0, 1.0, pts.iter().copied()), 80.0);
        assert_eq!(l.wall_length(2, 1.0, pts.iter().copied()), 90.0);
        let mut open = l.clone();
        open.walls.truncate(2);
        assert_eq!(open.wall_length(0, 1.0, pts.iter().copied()), 7.0);
        assert_eq!(open.die(0.0), None);
        assert_eq!(open.wall_plane(1, 1.0), ([90.0, 0.0], [-1.0, 0.0]));
    }
}
