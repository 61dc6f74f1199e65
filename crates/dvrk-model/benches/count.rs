//! Instruction counts per call, the comparison with Pinocchio that the machine's load does
//! not change: `ROBOT OP ITERATIONS` calls one real-time algorithm `ITERATIONS` times on
//! the state and parameters of `benches/dynamics.rs`, so that
//!
//! ```sh
//! cargo bench -p dvrk-model --bench count --no-run   # prints the executable's path
//! for k in 1000 3000; do
//!   valgrind --tool=cachegrind --cache-sim=no target/release/deps/count-HASH panda mass $k
//! done   # (I refs of the second − of the first) / 2000 = instructions per call
//! ```
//!
//! `ROBOT`: psm, mtm or panda (`../shared/anchors/panda_arm_7dof.urdf`); `OP`: mass
//! (`mass_matrix_into`), forward (`forward_dynamics_into`), inverse
//! (`inverse_dynamics`), nonlinear (`nonlinear_effects`), observer (one
//! `MomentumObserver::update` at 1 kHz, as the `momentum observer` bench). Pinocchio's side: `pinocchio/count.cpp`. Without arguments (as
//! `cargo bench` runs every bench) it does nothing.

use std::hint::black_box;

use dvrk_model::{Model, MomentumObserver, Workspace};

mod common;
use common::{physical, sample, PANDA};

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    let [robot, op, iterations] = args.as_slice() else {
        return;
    };
    let model = if robot == "panda" {
        Model::load(PANDA).expect("the Panda URDF of ../shared/anchors")
    } else {
        Model::builtin(robot).expect("psm, mtm or panda")
    };
    let iterations: usize = iterations.parse().expect("a number of iterations");
    let n = model.dof();
    let mut ws = Workspace::new(&model);
    let params = physical(&model);
    let (q, dq, ddq) = (sample(n, 1.0), sample(n, 2.0), sample(n, -1.0));
    let (mut tau, mut acc, mut m) = (vec![0.0; n], vec![0.0; n], vec![0.0; n * n]);
    model.inverse_dynamics(&mut ws, &params, &q, &dq, &ddq, &mut tau);
    let applied = tau.clone();
    let mut observer = MomentumObserver::new(&model, &vec![50.0; n]).expect("gains");
    for _ in 0..iterations {
        match op.as_str() {
            "mass" => model.mass_matrix_into(&mut ws, &params, black_box(&q), &mut m),
            "forward" => model
                .forward_dynamics_into(&mut ws, &params, black_box(&q), &dq, &applied, &mut acc)
                .expect("physical parameters"),
            "inverse" => {
                model.inverse_dynamics(&mut ws, &params, black_box(&q), &dq, &ddq, &mut tau)
            }
            "nonlinear" => model.nonlinear_effects(&mut ws, &params, black_box(&q), &dq, &mut tau),
            "observer" => {
                let r =
                    observer.update(&model, &mut ws, &params, black_box(&q), &dq, &applied, 1e-3);
                black_box(r);
            }
            _ => panic!("OP is mass, forward, inverse, nonlinear or observer"),
        }
        black_box((&m, &acc, &tau));
    }
}
