//! How datagrams move: a [`Transport`] sends bytes and receives bytes without blocking.
//!
//! Three implementations:
//! - [`UdpTransport`]: a non-blocking `std::net::UdpSocket`, either connected to a fixed
//!   peer (the controller's side) or listening and learning its peer from the first valid
//!   datagram (the plant's side; [`Transport::accept_peer`]). Once learned, the peer is
//!   kept, and datagrams from any other address are skipped and counted
//!   ([`UdpTransport::foreign`]).
//! - [`channel_pair`]: two in-process ends for deterministic single-threaded lock step;
//!   what one end sends at tick `n` the other receives at its next poll. Each direction
//!   is a queue with its capacity reserved up front; a full queue refuses the datagram
//!   like a full socket buffer ([`TransportError::WouldBlock`]).
//! - [`Faulty`]: any transport whose sending side passes through a [`FaultInjector`].
//!
//! Contracts: `send` and `try_recv` never block and never allocate (after
//! construction); `try_recv` gives one whole datagram per call, cut to the buffer's
//! length if longer (as UDP does), so receivers use a buffer of [`MAX_DATAGRAM`] bytes.

use std::cell::RefCell;
use std::collections::VecDeque;
use std::io;
use std::net::{SocketAddr, ToSocketAddrs, UdpSocket};
use std::rc::Rc;

use rigtwin_device::{ErrorKind, Tick};

use crate::faults::{FaultInjector, MAX_DATAGRAM};

/// Why a transport could not send or receive.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum TransportError {
    /// The outgoing buffer is full; the datagram was not sent.
    #[error("send buffer full")]
    WouldBlock,
    /// A listening end has not learned its peer yet; the datagram was not sent.
    #[error("no peer known yet")]
    NoPeer,
    /// The other in-process end has been dropped.
    #[error("the other end is gone")]
    PeerGone,
    /// The operating system reported an error.
    #[error("socket error: {0}")]
    Io(io::ErrorKind),
}

impl TransportError {
    /// The hardware-error class the controller sees.
    #[must_use]
    pub fn kind(&self) -> ErrorKind {
        match self {
            TransportError::WouldBlock => ErrorKind::Timeout,
            TransportError::NoPeer | TransportError::PeerGone => ErrorKind::Disconnected,
            TransportError::Io(k) => match k {
                io::ErrorKind::ConnectionRefused
                | io::ErrorKind::ConnectionReset
                | io::ErrorKind::ConnectionAborted
                | io::ErrorKind::NotConnected
                | io::ErrorKind::BrokenPipe
                | io::ErrorKind::AddrNotAvailable
                | io::ErrorKind::NetworkUnreachable
                | io::ErrorKind::HostUnreachable
                | io::ErrorKind::NetworkDown => ErrorKind::Disconnected,
                io::ErrorKind::TimedOut => ErrorKind::Timeout,
                _ => ErrorKind::Other,
            },
        }
    }

    /// `true` when only this datagram was not sent and the link may still be fine.
    #[must_use]
    pub fn is_unsent(&self) -> bool {
        matches!(self, TransportError::WouldBlock | TransportError::NoPeer)
    }
}

/// Sends and receives whole datagrams without blocking.
pub trait Transport {
    /// Sends one datagram at the sender's tick `now` (plain transports ignore `now`; a
    /// [`Faulty`] one schedules by it).
    fn send(&mut self, now: Tick, bytes: &[u8]) -> Result<(), TransportError>;

    /// Receives one pending datagram into `buf` and returns its length, or `None` if
    /// nothing is pending.
    fn try_recv(&mut self, buf: &mut [u8]) -> Result<Option<usize>, TransportError>;

    /// Tells the transport that the datagram last received was valid, so a listening end
    /// may adopt its sender as the peer. Does nothing on transports with a fixed peer.
    fn accept_peer(&mut self) {}
}

#[derive(Debug, Clone, Copy)]
enum Peer {
    Fixed,
    Learn {
        peer: Option<SocketAddr>,
        last_source: Option<SocketAddr>,
    },
}

/// A non-blocking UDP socket with a fixed or learned peer.
#[derive(Debug)]
pub struct UdpTransport {
    socket: UdpSocket,
    peer: Peer,
    foreign: u64,
}

impl UdpTransport {
    /// How many foreign datagrams one `try_recv` skips at most before reporting nothing
    /// pending, so that a flood cannot hold a tick.
    const MAX_SKIPPED: usize = 64;

    /// Binds `local` (port 0 for any) and connects to `peer`: the controller's side.
    pub fn connect(local: impl ToSocketAddrs, peer: SocketAddr) -> io::Result<UdpTransport> {
        let socket = UdpSocket::bind(local)?;
        socket.connect(peer)?;
        socket.set_nonblocking(true)?;
        Ok(UdpTransport {
            socket,
            peer: Peer::Fixed,
            foreign: 0,
        })
    }

    /// Binds `local` and learns the peer from the first valid datagram: the plant's side.
    pub fn listen(local: impl ToSocketAddrs) -> io::Result<UdpTransport> {
        let socket = UdpSocket::bind(local)?;
        socket.set_nonblocking(true)?;
        Ok(UdpTransport {
            socket,
            peer: Peer::Learn {
                peer: None,
                last_source: None,
            },
            foreign: 0,
        })
    }

    /// The address the socket is bound to.
    pub fn local_addr(&self) -> io::Result<SocketAddr> {
        self.socket.local_addr()
    }

    /// The peer: the connected one, or the learned one (`None` until learned).
    #[must_use]
    pub fn peer(&self) -> Option<SocketAddr> {
        match self.peer {
            Peer::Fixed => self.socket.peer_addr().ok(),
            Peer::Learn { peer, .. } => peer,
        }
    }

    /// Datagrams skipped because they came from another address than the learned peer.
    #[must_use]
    pub fn foreign(&self) -> u64 {
        self.foreign
    }
}

fn map_send(r: io::Result<usize>) -> Result<(), TransportError> {
    match r {
        Ok(_) => Ok(()),
        Err(e) if e.kind() == io::ErrorKind::WouldBlock => Err(TransportError::WouldBlock),
        Err(e) => Err(TransportError::Io(e.kind())),
    }
}

impl Transport for UdpTransport {
    fn send(&mut self, _now: Tick, bytes: &[u8]) -> Result<(), TransportError> {
        match self.peer {
            Peer::Fixed => map_send(self.socket.send(bytes)),
            Peer::Learn { peer: Some(p), .. } => map_send(self.socket.send_to(bytes, p)),
            Peer::Learn { peer: None, .. } => Err(TransportError::NoPeer),
        }
    }

    fn try_recv(&mut self, buf: &mut [u8]) -> Result<Option<usize>, TransportError> {
        for _ in 0..Self::MAX_SKIPPED {
            let r = match self.peer {
                Peer::Fixed => self.socket.recv(buf).map(|n| (n, None)),
                Peer::Learn { .. } => self.socket.recv_from(buf).map(|(n, a)| (n, Some(a))),
            };
            let (n, source) = match r {
                Ok(x) => x,
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => return Ok(None),
                Err(e) => return Err(TransportError::Io(e.kind())),
            };
            if let Peer::Learn { peer, last_source } = &mut self.peer {
                if peer.is_some() && *peer != source {
                    self.foreign += 1;
                    continue;
                }
                *last_source = source;
            }
            return Ok(Some(n));
        }
        Ok(None)
    }

    fn accept_peer(&mut self) {
        if let Peer::Learn { peer, last_source } = &mut self.peer
            && peer.is_none()
        {
            *peer = *last_source;
        }
    }
}

#[derive(Debug)]
struct Queue {
    items: VecDeque<(usize, [u8; MAX_DATAGRAM])>,
    capacity: usize,
}

/// One end of an in-process lock-step link (see [`channel_pair`]).
#[derive(Debug)]
pub struct ChannelEnd {
    tx: Rc<RefCell<Queue>>,
    rx: Rc<RefCell<Queue>>,
}

/// Two connected in-process ends; each direction holds up to `capacity` datagrams of at
/// most [`MAX_DATAGRAM`] bytes, reserved here. Single-threaded: the ends are not `Send`.
#[must_use]
pub fn channel_pair(capacity: usize) -> (ChannelEnd, ChannelEnd) {
    let queue = || {
        Rc::new(RefCell::new(Queue {
            items: VecDeque::with_capacity(capacity),
            capacity,
        }))
    };
    let (a_to_b, b_to_a) = (queue(), queue());
    (
        ChannelEnd {
            tx: Rc::clone(&a_to_b),
            rx: Rc::clone(&b_to_a),
        },
        ChannelEnd {
            tx: b_to_a,
            rx: a_to_b,
        },
    )
}

impl ChannelEnd {
    /// Datagrams waiting to be received at this end.
    #[must_use]
    pub fn pending(&self) -> usize {
        self.rx.try_borrow().map_or(0, |q| q.items.len())
    }
}

impl Transport for ChannelEnd {
    fn send(&mut self, _now: Tick, bytes: &[u8]) -> Result<(), TransportError> {
        if Rc::strong_count(&self.tx) < 2 {
            return Err(TransportError::PeerGone);
        }
        let mut q = self
            .tx
            .try_borrow_mut()
            .map_err(|_| TransportError::Io(io::ErrorKind::ResourceBusy))?;
        if q.items.len() >= q.capacity {
            return Err(TransportError::WouldBlock);
        }
        let len = bytes.len().min(MAX_DATAGRAM);
        let mut slot = [0u8; MAX_DATAGRAM];
        slot[..len].copy_from_slice(&bytes[..len]);
        q.items.push_back((len, slot));
        Ok(())
    }

    fn try_recv(&mut self, buf: &mut [u8]) -> Result<Option<usize>, TransportError> {
        let mut q = self
            .rx
            .try_borrow_mut()
            .map_err(|_| TransportError::Io(io::ErrorKind::ResourceBusy))?;
        Ok(q.items.pop_front().map(|(len, slot)| {
            let n = len.min(buf.len());
            buf[..n].copy_from_slice(&slot[..n]);
            n
        }))
    }
}

/// A transport whose outgoing datagrams pass through a [`FaultInjector`]; receiving is
/// untouched. Delayed datagrams leave on the first `send` at or after their due tick, so
/// the sender must send every tick (both ends do).
#[derive(Debug)]
pub struct Faulty<T: Transport> {
    inner: T,
    injector: FaultInjector,
}

impl<T: Transport> Faulty<T> {
    /// Wraps `inner`'s sending side with `injector`.
    #[must_use]
    pub fn new(inner: T, injector: FaultInjector) -> Faulty<T> {
        Faulty { inner, injector }
    }

    /// The injector (its counters say what it did).
    #[must_use]
    pub fn injector(&self) -> &FaultInjector {
        &self.injector
    }

    /// The wrapped transport.
    #[must_use]
    pub fn inner(&self) -> &T {
        &self.inner
    }
}

impl<T: Transport> Transport for Faulty<T> {
    /// Offers the datagram to the injector, then sends everything due at `now`. Returns
    /// the first error of those sends, after trying them all.
    fn send(&mut self, now: Tick, bytes: &[u8]) -> Result<(), TransportError> {
        self.injector.offer(now, bytes);
        let mut result = Ok(());
        while let Some(due) = self.injector.next_due(now) {
            let r = self.inner.send(now, due);
            if result.is_ok() {
                result = r;
            }
        }
        result
    }

    fn try_recv(&mut self, buf: &mut [u8]) -> Result<Option<usize>, TransportError> {
        self.inner.try_recv(buf)
    }

    fn accept_peer(&mut self) {
        self.inner.accept_peer();
    }
}
