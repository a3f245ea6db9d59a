//! Where the viewer data goes: the value of `--rerun`.

use std::fmt;
use std::path::PathBuf;
use std::str::FromStr;

/// The port a rerun viewer listens on unless told otherwise.
pub const DEFAULT_PORT: u16 = 9876;

/// Where to send viewer data, parsed from `--rerun spawn | save=<file.rrd> | connect[=<addr>]`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Target {
    /// Start a rerun viewer (the `rerun` executable on `PATH`) and stream to it.
    Spawn,
    /// Write every sample to an `.rrd` file.
    Save(PathBuf),
    /// Stream to a running viewer at this gRPC proxy URL (`rerun+http://host:port/proxy`).
    Connect(String),
}

/// A `--rerun` value that is none of the accepted forms.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "invalid --rerun value `{value}`: {reason}; expected `spawn`, `save=<file.rrd>` or \
     `connect[=<host:port> | =rerun+http://<host:port>/proxy]`"
)]
pub struct TargetParseError {
    value: String,
    reason: &'static str,
}

impl TargetParseError {
    fn new(value: &str, reason: &'static str) -> Self {
        Self {
            value: value.to_owned(),
            reason,
        }
    }
}

impl FromStr for Target {
    type Err = TargetParseError;

    fn from_str(value: &str) -> Result<Self, Self::Err> {
        let (kind, arg) = match value.split_once('=') {
            Some((kind, arg)) => (kind, Some(arg)),
            None => (value, None),
        };
        match (kind, arg) {
            ("spawn", None) => Ok(Self::Spawn),
            ("spawn", Some(_)) => Err(TargetParseError::new(value, "`spawn` takes no value")),
            ("save", None) => Err(TargetParseError::new(
                value,
                "`save` needs a file: save=<file.rrd>",
            )),
            ("save", Some(path)) => parse_save(value, path),
            ("connect", None) => Ok(Self::Connect(proxy_url(&format!(
                "127.0.0.1:{DEFAULT_PORT}"
            )))),
            ("connect", Some(addr)) => parse_connect(value, addr),
            _ => Err(TargetParseError::new(value, "unknown target")),
        }
    }
}

fn parse_save(value: &str, path: &str) -> Result<Target, TargetParseError> {
    if path.trim().is_empty() {
        return Err(TargetParseError::new(value, "`save=` needs a file name"));
    }
    let path = PathBuf::from(path);
    if path.extension().is_none_or(|ext| ext != "rrd") {
        return Err(TargetParseError::new(
            value,
            "the file must end in `.rrd` (the viewer recognises recordings by it)",
        ));
    }
    Ok(Target::Save(path))
}

fn parse_connect(value: &str, addr: &str) -> Result<Target, TargetParseError> {
    let url = if addr.contains("://") {
        addr.to_owned()
    } else {
        let Some((host, port)) = addr.rsplit_once(':') else {
            return Err(TargetParseError::new(
                value,
                "the address needs a port: <host:port>",
            ));
        };
        if host.is_empty() {
            return Err(TargetParseError::new(
                value,
                "the address needs a host: <host:port>",
            ));
        }
        if port.parse::<u16>().is_err() {
            return Err(TargetParseError::new(
                value,
                "the port must be a number from 0 to 65535",
            ));
        }
        proxy_url(addr)
    };
    if url.parse::<rerun::external::re_uri::ProxyUri>().is_err() {
        return Err(TargetParseError::new(
            value,
            "not a rerun proxy URL (rerun+http://<host:port>/proxy)",
        ));
    }
    Ok(Target::Connect(url))
}

fn proxy_url(addr: &str) -> String {
    format!("rerun+http://{addr}/proxy")
}

impl fmt::Display for Target {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Spawn => write!(f, "spawn"),
            Self::Save(path) => write!(f, "save={}", path.display()),
            Self::Connect(url) => write!(f, "connect={url}"),
        }
    }
}

impl Target {
    /// Whether the data goes to a live viewer (which may be sent fewer samples).
    pub fn is_live(&self) -> bool {
        matches!(self, Self::Spawn | Self::Connect(_))
    }
}

/// The `--rerun` option, to `#[command(flatten)]` into every command that runs or reads a
/// session.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct RerunArgs {
    /// Show the session in the rerun viewer: `spawn` starts a viewer, `save=<file.rrd>` writes
    /// every sample to a file (open it with `rerun <file.rrd>`), `connect[=<host:port>]` streams
    /// to a running viewer (default 127.0.0.1:9876).
    #[arg(long, value_name = "spawn|save=FILE.rrd|connect[=ADDR]")]
    pub rerun: Option<Target>,
}
