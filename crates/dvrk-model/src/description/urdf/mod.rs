//! URDF in both directions, for the tools that read URDF rather than our descriptions
//! (Pinocchio, KDL, RBDL, Drake, Gazebo, MuJoCo's importer). [`import`] reads a URDF into a
//! model. The identified parameters go out in two ways, because a robot's URDF is usually
//! much more than its dynamics: [`replace`] puts them into the URDF a model was imported
//! from and changes nothing else, [`generate`] writes a new URDF of a whole description.
//! Both take the inertials through [`inertials`], which refuses what a URDF link cannot
//! hold. Numbers are written with Rust's shortest round-trip formatting, so the written
//! values are the computed ones.

mod generate;
mod import;
mod inertials;
mod replace;
