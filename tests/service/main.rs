//! The HTTP service over real HTTP on 127.0.0.1 against a temporary SQLite file:
//! a job's life through the API, requests and their errors, event streams, where
//! the bytes of results live, and the viewer page in a headless browser. One test
//! binary: each binary that starts the service compiles its HTTP stack again (about
//! a minute of CI's build per binary).

mod clients;
#[path = "../common/mod.rs"]
mod common;
mod contract;
mod isolation;
mod keys;
mod lifecycle;
mod nodes;
mod operations;
mod requests;
mod results;
mod storage;
mod streams;
mod viewer;

use common::server::*;
use common::validate_gltf;
use serde_json::Value;
use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::time::{Duration, Instant};

const CIRCLE: &str = r#"{"problem": {"type": "curvature_flow"},
    "initial": {"shape": "circle", "radius": 1.0, "resolution": 64},
    "flow": {"tau": 1e-3, "end_time": 0.1, "max_iterations": 100000, "tolerance": 0},
    "output": {"checkpoint_every": 20}}"#;

const LONG: &str = r#"{"problem": {"type": "surface_diffusion"},
    "initial": {"shape": "ellipse", "semi_axes": [1.0, 0.5], "resolution": 128},
    "flow": {"tau": 1e-6, "end_time": 0.02, "max_iterations": 1000000},
    "mesh": {"adapt": false, "regularize": false, "topology_changes": false},
    "output": {"checkpoint_every": 200}}"#;
