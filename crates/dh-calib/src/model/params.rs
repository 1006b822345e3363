//! What a parameter of the model is: its name, block, field and unit (metres, radians or an
//! effect's own unit).

/// Physical kind of a parameter, which decides its column scale.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Unit {
    /// Metres.
    Length,
    /// Radians.
    Angle,
    /// Defined by the effect that owns the parameter.
    Other,
}

/// Which part of the model a parameter belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Block {
    /// The device frame (`T_device_base`).
    Device,
    /// The device frame of measurement session `s` (index into
    /// [`crate::data::Measurements::sessions`]) when it is not the first calibration session,
    /// which uses [`Block::Device`] (see [`crate::sessions`]).
    Session(usize),
    /// The table's base transform.
    Base,
    /// A row of the table (index into its rows).
    Joint(usize),
    /// The table's tool transform.
    Tool,
    /// A tree branch's mount (index into the tree's branches).
    Mount(usize),
    /// A target (index into the target list).
    Target(usize),
    /// An effect (index in the order added).
    Effect(usize),
}

/// Which quantity of its block a parameter is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Field {
    /// Translation along x (metres).
    X,
    /// Translation along y (metres).
    Y,
    /// Translation along z (metres).
    Z,
    /// Rotation about x (radians).
    Rx,
    /// Rotation about y (radians).
    Ry,
    /// Rotation about z (radians).
    Rz,
    /// DH link length error (metres).
    A,
    /// DH link twist error (radians).
    Alpha,
    /// DH link offset error (metres).
    D,
    /// DH joint angle offset error (radians).
    Theta,
    /// Hayati-Mirmirani tilt about y (radians).
    Beta,
    /// The effect's `k`-th parameter.
    Effect(usize),
}

/// One estimable quantity of a [`Model`](super::Model).
#[derive(Clone, Debug, PartialEq)]
pub struct Parameter {
    /// Name, part of the report's contract (see the module docs).
    pub name: String,
    /// What it belongs to.
    pub block: Block,
    /// Which quantity.
    pub field: Field,
    /// Its unit.
    pub unit: Unit,
}
