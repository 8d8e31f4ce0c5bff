//! The PostgreSQL server of a cluster test: Debian's server programs, initdb and
//! pg_ctl in a temporary directory, on 127.0.0.1.

use std::path::PathBuf;
use std::process::Command;

/// The directory of PostgreSQL's server programs, if installed.
fn pg_bin() -> Option<PathBuf> {
    let candidates =
        std::fs::read_dir("/usr/lib/postgresql").ok()?.filter_map(|e| e.ok()).map(|e| e.path().join("bin"));
    let mut found: Vec<PathBuf> = candidates.filter(|b| b.join("pg_ctl").exists()).collect();
    found.sort();
    found.pop()
}

pub fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

/// A PostgreSQL server in a temporary directory (run as the `postgres` user when
/// the test runs as root, since the server refuses root).
pub struct Postgres {
    bin: PathBuf,
    dir: tempfile::TempDir,
    port: u16,
    as_root: bool,
}

impl Postgres {
    pub fn start() -> Option<Postgres> {
        let bin = pg_bin()?;
        let dir = tempfile::tempdir().unwrap();
        let as_root = unsafe { libc::geteuid() } == 0;
        if as_root {
            let mut perms = std::fs::metadata(dir.path()).unwrap().permissions();
            std::os::unix::fs::PermissionsExt::set_mode(&mut perms, 0o777);
            std::fs::set_permissions(dir.path(), perms).unwrap();
        }
        let pg = Postgres { bin, dir, port: free_port(), as_root };
        let data = pg.dir.path().join("data");
        pg.run("initdb", &["-D", data.to_str().unwrap(), "-U", "postgres", "-A", "trust", "--no-sync"]);
        pg.ctl("start");
        Some(pg)
    }

    /// A command running the server program `program` (as `postgres` under root).
    fn command(&self, program: &str) -> Command {
        let exe = self.bin.join(program);
        if self.as_root {
            let mut c = Command::new("runuser");
            c.args(["-u", "postgres", "--"]).arg(&exe);
            c
        } else {
            Command::new(&exe)
        }
    }

    fn run(&self, program: &str, args: &[&str]) {
        let out = self.command(program).args(args).current_dir(self.dir.path()).output().unwrap();
        assert!(out.status.success(), "{program}: {}", String::from_utf8_lossy(&out.stderr));
    }

    pub fn ctl(&self, action: &str) {
        let data = self.dir.path().join("data");
        let dir = self.dir.path().to_str().unwrap();
        let options = format!("-k {dir} -p {} -c listen_addresses=127.0.0.1 -c fsync=off", self.port);
        let log = self.dir.path().join("log");
        let mut args = vec!["-D", data.to_str().unwrap(), "-l", log.to_str().unwrap(), "-w", "-m", "fast"];
        if action != "stop" {
            args.extend(["-o", &options]);
        }
        args.push(action);
        self.run("pg_ctl", &args);
    }

    pub fn url(&self) -> String {
        format!("postgres://postgres@127.0.0.1:{}/postgres", self.port)
    }
}

impl Drop for Postgres {
    fn drop(&mut self) {
        let data = self.dir.path().join("data");
        let _ = self.command("pg_ctl").args(["-D", data.to_str().unwrap(), "-m", "immediate", "stop"]).output();
    }
}
