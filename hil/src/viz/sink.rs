//! Where the chunks go: a live viewer through rerun's `RecordingStream`, or rerun's `.rrd`
//! encoder writing a file or a buffer.
//!
//! Files and buffers are written by rerun's encoder directly (on a thread of our own that
//! takes the chunks in order) instead of through the SDK's batcher and file-writer thread: the SDK stamps its store-info message
//! with a clock-based id and lets the flush timer decide chunk boundaries, which makes two
//! saves of the same data differ. Writing ourselves keeps every byte a function of the input,
//! and an I/O error reaches the caller instead of a log line.

use std::fs::File;
use std::io::{BufWriter, Write as _};
use std::path::PathBuf;
use std::sync::mpsc::{SyncSender, sync_channel};
use std::thread::JoinHandle;
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
    /// A file or a buffer, encoded on a background thread.
    Encoded(Background),
}

/// What the encoding thread is sent, in order.
enum Item {
    Msg(LogMsg),
    Chunk(StoreId, Chunk),
}

/// Messages waiting for the encoder at most: enough to keep it busy, bounded so that a slow
/// disk holds the producer back instead of memory growing.
const QUEUE: usize = 256;

/// The encoder on its own thread: the caller builds chunks while the previous ones are
/// serialised, compressed and written (on 2 cores this takes most of the encoding off the
/// caller's wall time). Messages keep their order, so the bytes are those of encoding on
/// the caller's thread.
pub(crate) struct Background {
    tx: Option<SyncSender<Item>>,
    handle: Option<JoinHandle<Result<Option<Vec<u8>>, VizError>>>,
    what: String,
}

impl Background {
    fn spawn<W, F>(mut encoder: Encoder<W>, what: String, finish: F) -> Result<Self, VizError>
    where
        W: std::io::Write + Send + 'static,
        F: FnOnce(W) -> Result<Option<Vec<u8>>, VizError> + Send + 'static,
    {
        let (tx, rx) = sync_channel::<Item>(QUEUE);
        let handle = std::thread::Builder::new()
            .name("rrd-encoder".to_owned())
            .spawn(move || {
                for item in rx {
                    let msg = match item {
                        Item::Msg(msg) => msg,
                        Item::Chunk(store_id, chunk) => {
                            let entity = chunk.entity_path().to_string();
                            let arrow = chunk
                                .to_arrow_msg()
                                .map_err(|source| VizError::Chunk { entity, source })?;
                            LogMsg::ArrowMsg(store_id, arrow)
                        }
                    };
                    encoder.append(&msg)?;
                }
                encoder.finish()?;
                finish(encoder.into_inner()?)
            })
            .map_err(|source| VizError::Io {
                path: PathBuf::from(&what),
                source,
            })?;
        Ok(Self {
            tx: Some(tx),
            handle: Some(handle),
            what,
        })
    }

    fn send(&mut self, item: Item) -> Result<(), VizError> {
        let sent = self.tx.as_ref().is_some_and(|tx| tx.send(item).is_ok());
        if sent {
            return Ok(());
        }
        // The thread stopped: it returns why.
        self.tx = None;
        match self.join() {
            Err(err) => Err(err),
            Ok(_) => Err(VizError::Flush(format!(
                "the encoder of {} stopped early",
                self.what
            ))),
        }
    }

    fn join(&mut self) -> Result<Option<Vec<u8>>, VizError> {
        self.tx = None;
        match self.handle.take() {
            Some(handle) => handle.join().unwrap_or_else(|_| {
                Err(VizError::Flush(format!(
                    "the encoder of {} panicked",
                    self.what
                )))
            }),
            None => Err(VizError::Flush(format!(
                "the encoder of {} has already stopped",
                self.what
            ))),
        }
    }
}

impl Drop for Background {
    fn drop(&mut self) {
        self.tx = None;
        if let Some(handle) = self.handle.take() {
            let _ = handle.join();
        }
    }
}

impl std::fmt::Debug for Sink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Live(rec) => f.debug_tuple("Live").field(rec).finish(),
            Self::Encoded(b) => f.debug_struct("Encoded").field("to", &b.what).finish(),
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
    /// Creates the file (and its folder, as `--out` is created: a rehearsal opens its
    /// `.rrd` before it writes its sessions).
    pub(crate) fn file(path: PathBuf) -> Result<Self, VizError> {
        if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
            std::fs::create_dir_all(parent).map_err(|source| VizError::Io {
                path: parent.to_path_buf(),
                source,
            })?;
        }
        let file = File::create(&path).map_err(|source| VizError::Io {
            path: path.clone(),
            source,
        })?;
        let what = path.display().to_string();
        let encoder = encoder(BufWriter::new(file))?;
        Ok(Self::Encoded(Background::spawn(
            encoder,
            what,
            move |mut write| {
                write
                    .flush()
                    .map_err(|source| VizError::Io { path, source })?;
                Ok(None)
            },
        )?))
    }

    pub(crate) fn memory() -> Result<Self, VizError> {
        Ok(Self::Encoded(Background::spawn(
            encoder(Vec::new())?,
            "a memory buffer".to_owned(),
            |bytes| Ok(Some(bytes)),
        )?))
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
        self.append(msg)
    }

    fn append(&mut self, msg: LogMsg) -> Result<(), VizError> {
        match self {
            Self::Live(rec) => {
                rec.record_msg(msg);
                Ok(())
            }
            Self::Encoded(b) => b.send(Item::Msg(msg)),
        }
    }

    pub(crate) fn send(&mut self, store_id: &StoreId, chunk: Chunk) -> Result<(), VizError> {
        match self {
            Self::Live(rec) => {
                rec.send_chunk(chunk);
                Ok(())
            }
            Self::Encoded(b) => b.send(Item::Chunk(store_id.clone(), chunk)),
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
        for msg in messages {
            self.append(msg)?;
        }
        self.append(LogMsg::BlueprintActivationCommand(activation))
    }

    /// Ends the stream: writes the footer and flushes. Returns the bytes of a memory sink.
    pub(crate) fn finish(self) -> Result<Option<Vec<u8>>, VizError> {
        match self {
            Self::Live(rec) => match rec.flush_with_timeout(LIVE_FLUSH_TIMEOUT) {
                Ok(()) => Ok(None),
                Err(err) => {
                    // Dropping the stream joins its sender thread, which stays blocked
                    // on a viewer that stopped reading: the error would never be told.
                    // The process ends with this error, so the stream is left to it.
                    std::mem::forget(rec);
                    Err(VizError::Flush(err.to_string()))
                }
            },
            Self::Encoded(mut b) => b.join(),
        }
    }
}
