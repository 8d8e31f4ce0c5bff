//! The `shapeflow` command: `run` a job spec offline, or `serve` the HTTP API
//! (the subcommands in `cli/`).

mod cli;

use clap::Parser;
use cli::args::{Cli, Command, LogFormat};
use cli::keys::keys;
use cli::run::{run, say};
use cli::serve::{init_logs, serve, token_from};
use std::process::ExitCode;

fn main() -> ExitCode {
    shapeflow::tune_allocator();
    let cli = Cli::parse();
    init_logs(match &cli.command {
        Command::Serve { node, .. } | Command::Worker { node } => node.log_format,
        _ => LogFormat::Text,
    });
    match cli.command {
        Command::JobRunner { memory } => shapeflow::service::isolation::child::job_runner(memory),
        Command::Run { spec, out, inputs, resume } => match run(&spec, &out, &inputs, resume.as_deref()) {
            Ok(code) => code,
            Err(e) => {
                eprintln!("error: {e:#}");
                ExitCode::from(2)
            }
        },
        Command::Schema { markdown } => {
            let schema = shapeflow::jobs::job_spec_schema();
            if markdown {
                say(format_args!("{}", shapeflow::jobs::job_spec_reference(&schema).trim_end()));
            } else {
                let text = serde_json::to_string_pretty(&schema).expect("a schema is JSON");
                say(format_args!("{text}"));
            }
            ExitCode::SUCCESS
        }
        Command::Serve { bind, node, token, token_file, cors_origins, http } => {
            let config = token_from(token, token_file.as_deref()).and_then(|t| node.config(t, true));
            let result = config.and_then(|config| {
                let config = shapeflow::service::ServiceConfig { cors_origins, ..config };
                let limits = http.limits()?;
                let rt = tokio::runtime::Builder::new_multi_thread().enable_all().build()?;
                rt.block_on(serve(Some((&bind, limits)), config))
            });
            match result {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("error: {e:#}");
                    ExitCode::from(1)
                }
            }
        }
        Command::Keys { action, store } => match keys(action, &store) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("error: {e:#}");
                ExitCode::from(1)
            }
        },
        Command::Health { url } => {
            let url = url.trim_start_matches("http://");
            let (addr, path) = url.find('/').map_or((url, "/readyz"), |i| (&url[..i], &url[i..]));
            match shapeflow::service::http::probe(addr, path, std::time::Duration::from_secs(5)) {
                Ok(200) => ExitCode::SUCCESS,
                Ok(status) => {
                    eprintln!("{url}: {status}");
                    ExitCode::from(1)
                }
                Err(e) => {
                    eprintln!("{url}: {e}");
                    ExitCode::from(1)
                }
            }
        }
        Command::Worker { node } => {
            let result = node.config(None, false).and_then(|config| {
                let rt = tokio::runtime::Builder::new_multi_thread().enable_all().build()?;
                rt.block_on(serve(None, config))
            });
            match result {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("error: {e:#}");
                    ExitCode::from(1)
                }
            }
        }
    }
}
