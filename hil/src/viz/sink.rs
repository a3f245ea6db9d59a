//! Where the chunks go: a live viewer through rerun's `RecordingStream`, or rerun's `.rrd`
//! encoder writing a file or a buffer.
//!
//! Files and buffers are written by the encoder directly, on the caller's thread, instead of
//! through the SDK's batcher and file-writer thread: the SDK stamps its store-info message
//! with a clock-based id and lets the flush timer decide chunk boundaries, which makes two
//! saves of the same data differ. Writing ourselves keeps every byte a function of the input,
//! and an I/O error reaches the caller instead of a log line.

use std::fs::File;
use std::io::{BufWriter, Write as _};
use std::path::PathBuf;
use std::time::Duration;

use rerun::RecordingStream;
use rerun::external::re_build_info::CrateVersion;
use rerun::external::re_log_encoding::{Encoder, EncodingOptions};
use rerun::external::re_log_types::{
    BlueprintActivationCommand, LogMsg, SetStoreInfo, StoreId, StoreInfo, StoreSource,
};
use rerun::log::{Chunk, RowId};

use super::VizError;

/// How long `finish` waits for a live viewer to take the last data.
const LIVE_FLUSH_TIMEOUT: Duration = Duration::from_secs(30);

pub(crate) enum Sink {
    Live(RecordingStream),
    File {
        encoder: Encoder<BufWriter<File>>,
        path: PathBuf,
    },
    Memory(Encoder<Vec<u8>>),
}

impl std::fmt::Debug for Sink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Live(rec) => f.debug_tuple("Live").field(rec).finish(),
            Self::File { path, .. } => f.debug_struct("File").field("path", path).finish(),
            Self::Memory(_) => f.write_str("Memory"),
        }
    }
}

/// The store source written into files: fixed, so that the compiler version does not leak
/// into the bytes.
pub(crate) fn store_source() -> StoreSource {
    StoreSource::Other(format!("rigtwin {}", env!("CARGO_PKG_VERSION")))
}

/// rerun's encoder with its footer (the per-store manifests that `rerun rrd verify` and
/// random access want). rerun 0.36 writes those manifests from a `HashMap`, so with two
/// stores (the recording and its blueprint) their order in the footer, and only there, can
/// differ between two saves; every message before it is the same bytes.
fn encoder<W: std::io::Write>(write: W) -> Result<Encoder<W>, VizError> {
    Ok(Encoder::new_eager(
        CrateVersion::LOCAL,
        EncodingOptions::PROTOBUF_COMPRESSED,
        write,
    )?)
}

impl Sink {
    pub(crate) fn file(path: PathBuf) -> Result<Self, VizError> {
        let file = File::create(&path).map_err(|source| VizError::Io {
            path: path.clone(),
            source,
        })?;
        Ok(Self::File {
            encoder: encoder(BufWriter::new(file))?,
            path,
        })
    }

    pub(crate) fn memory() -> Result<Self, VizError> {
        Ok(Self::Memory(encoder(Vec::new())?))
    }

    pub(crate) fn is_live(&self) -> bool {
        matches!(self, Self::Live(_))
    }

    /// Opens a store (the recording, or a blueprint) in an encoded stream. A live stream has
    /// already opened its recording.
    pub(crate) fn open_store(&mut self, store_id: &StoreId, row_id: RowId) -> Result<(), VizError> {
        let msg = LogMsg::SetStoreInfo(SetStoreInfo {
            row_id: *row_id,
            info: StoreInfo::new(store_id.clone(), store_source()),
        });
        self.append(&msg)
    }

    fn append(&mut self, msg: &LogMsg) -> Result<(), VizError> {
        match self {
            Self::Live(rec) => rec.record_msg(msg.clone()),
            Self::File { encoder, .. } => {
                encoder.append(msg)?;
            }
            Self::Memory(encoder) => {
                encoder.append(msg)?;
            }
        }
        Ok(())
    }

    pub(crate) fn send(&mut self, store_id: &StoreId, chunk: Chunk) -> Result<(), VizError> {
        match self {
            Self::Live(rec) => {
                rec.send_chunk(chunk);
                Ok(())
            }
            Self::File { .. } | Self::Memory(_) => {
                let entity = chunk.entity_path().to_string();
                let arrow = chunk
                    .to_arrow_msg()
                    .map_err(|source| VizError::Chunk { entity, source })?;
                self.append(&LogMsg::ArrowMsg(store_id.clone(), arrow))
            }
        }
    }

    /// Sends a complete blueprint store and the command that makes it the active layout.
    pub(crate) fn send_blueprint(
        &mut self,
        messages: Vec<LogMsg>,
        activation: BlueprintActivationCommand,
    ) -> Result<(), VizError> {
        if let Self::Live(rec) = self {
            rec.send_blueprint(messages, activation);
            return Ok(());
        }
        for msg in &messages {
            self.append(msg)?;
        }
        self.append(&LogMsg::BlueprintActivationCommand(activation))
    }

    /// Ends the stream: writes the footer and flushes. Returns the bytes of a memory sink.
    pub(crate) fn finish(self) -> Result<Option<Vec<u8>>, VizError> {
        match self {
            Self::Live(rec) => {
                rec.flush_with_timeout(LIVE_FLUSH_TIMEOUT)
                    .map_err(|err| VizError::Flush(err.to_string()))?;
                Ok(None)
            }
            Self::File { mut encoder, path } => {
                encoder.finish()?;
                let mut write = encoder.into_inner()?;
                write
                    .flush()
                    .map_err(|source| VizError::Io { path, source })?;
                Ok(None)
            }
            Self::Memory(mut encoder) => {
                encoder.finish()?;
                Ok(Some(encoder.into_inner()?))
            }
        }
    }
}
