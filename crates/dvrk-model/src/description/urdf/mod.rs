//! URDF in both directions: [`import`] reads a URDF into a model; [`generate`] writes the
//! identified parameters into the URDF a model was imported from, or a URDF of a whole
//! description.

mod generate;
mod import;
