//! What the `description` feature adds to the numeric core: models read from files
//! rather than built from numbers ([`ModelBuilder`](crate::ModelBuilder)), and models
//! written back as URDF. Off (`default-features = false`), none of this is compiled, and
//! with it go TOML, URDF, XML and serde.
//!
//! - [`robot`]: the TOML robot description (`robots/README.md`) into a [`Model`](crate::Model);
//! - [`resolve`]: numbers and expressions of a hand-written file against its constants and
//!   coordinates, each error named by file, place and field;
//! - [`elements`]: a frame's element keys (`friction`, `spring`...), resolved into the
//!   numeric constructor's [`ElementSpec`](crate::ElementSpec);
//! - [`limits`]: `[[limits]]` and `[[cartesian_limits]]`, in a description, a limits file
//!   or a Python dict, compiled into [`Limits`](crate::Limits);
//! - [`payload`]: the payload file (a rigid body fixed to a frame) into a
//!   [`Payload`](crate::Payload);
//! - [`builtin`]: the dVRK descriptions shipped with the crate, and loading by name or path;
//! - [`urdf`]: URDF import, and the two URDF exports (into an existing URDF, or generated).
//!
//! The rest of the crate never refers to this module, so the feature is this one `#[cfg]`
//! (and the re-exports of its public types at the crate root).

mod builtin;
mod elements;
mod limits;
mod payload;
mod resolve;
mod robot;
mod urdf;

pub use builtin::is_urdf_document;
pub use limits::{CartesianLimitSpec, JointLimitSpec, LimitsSpec};
