//! `lattice.operator`: the collision operator a scene chooses, and its Mach limit.

/// The collision operator of the lattice (`lattice.operator`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CollisionOperator {
    /// Single relaxation time (seed eq. 4).
    Bgk,
    /// Two relaxation times with TRT's magic parameter (the default).
    Trt,
    /// Multiple relaxation times on the d'Humieres moments.
    Mrt,
}

impl CollisionOperator {
    pub const ALL: [CollisionOperator; 3] = [Self::Bgk, Self::Trt, Self::Mrt];

    /// The name in scenes, summaries and messages.
    pub fn name(self) -> &'static str {
        match self {
            Self::Bgk => "bgk",
            Self::Trt => "trt",
            Self::Mrt => "mrt",
        }
    }

    pub fn named(name: &str) -> Option<CollisionOperator> {
        Self::ALL.into_iter().find(|o| o.name() == name)
    }
}

impl std::fmt::Display for CollisionOperator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Largest Mach number each operator accepts.
pub fn mach_limit(operator: CollisionOperator) -> f64 {
    match operator {
        CollisionOperator::Bgk => 0.3,
        CollisionOperator::Trt => 0.35,
        CollisionOperator::Mrt => 0.4,
    }
}
