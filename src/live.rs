//! The live view: a small Foxglove WebSocket server (subprotocol `foxglove.websocket.v1`,
//! <https://github.com/foxglove/ws-protocol/blob/main/docs/spec.md>) that Foxglove connects to
//! (`Open connection` → `Foxglove WebSocket` → `ws://HOST:PORT`) to watch a mission as it runs.
//!
//! Host only (feature `live`); opened only when asked (`papillon run --live ADDR`,
//! `papillon-sim mission --live ADDR`): without it nothing listens. The messages are the
//! recording's ([`crate::record::Recorder`] publishes every message it writes, same topics,
//! same JSON schemas), so what a viewer sees live is what the MCAP file replays afterwards.
//!
//! What the server does (the subset of the protocol a viewer needs):
//! - the handshake selects `foxglove.websocket.v1` when the client offers it;
//! - on connection it sends `serverInfo` (no capabilities) and `advertise` with every channel
//!   known so far; a channel that appears later (the first `/targets` at the first decision)
//!   is advertised to every connected client then;
//! - it answers `subscribe` (and `unsubscribe`) and sends each message of a subscribed channel as
//!   binary *message data* (opcode 1, subscription id u32 LE, log time ns u64 LE, the JSON);
//!   on subscribing, the channel's latest message is sent at once (the map is published only at
//!   decisions: a viewer opened between two would otherwise see none for a while).
//!
//! One thread accepts, one thread serves each viewer. A slow viewer never slows the mission:
//! each viewer has a bounded queue ([`QUEUE_MESSAGES`]) and a message that does not fit is
//! dropped for that viewer. Unknown or malformed client messages are ignored (logged at debug
//! level where `tracing` is present) and never end the mission.

use std::collections::BTreeMap;
use std::io;
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, SyncSender, TryRecvError, TrySendError, sync_channel};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread;
use std::time::Duration;

use serde_json::{Value, json};
use tungstenite::handshake::server::{ErrorResponse, Request, Response};
use tungstenite::{Message, WebSocket};

/// The WebSocket subprotocol the server speaks.
pub const SUBPROTOCOL: &str = "foxglove.websocket.v1";

/// Messages queued per viewer before newer ones are dropped for it.
pub const QUEUE_MESSAGES: usize = 1024;

/// How long a viewer's thread waits for the client before looking at its queue again.
const POLL: Duration = Duration::from_millis(10);

/// How long the WebSocket handshake may take.
const HANDSHAKE_TIMEOUT: Duration = Duration::from_secs(5);

/// A channel as advertised.
#[derive(Clone, Debug)]
struct Channel {
    id: u32,
    topic: String,
    schema_name: String,
    schema: String,
    /// The latest message: (log time ns, JSON).
    last: Option<(u64, Arc<[u8]>)>,
}

impl Channel {
    fn advertisement(&self) -> Value {
        json!({
            "id": self.id,
            "topic": self.topic,
            "encoding": "json",
            "schemaName": self.schema_name,
            "schema": self.schema,
            "schemaEncoding": "jsonschema",
        })
    }
}

/// What the publisher sends a viewer's thread.
#[derive(Debug)]
enum Outgoing {
    /// New channels to advertise (a JSON text message).
    Advertise(String),
    /// A message of channel `channel`.
    Data {
        channel: u32,
        t_ns: u64,
        data: Arc<[u8]>,
    },
}

#[derive(Debug, Default)]
struct State {
    channels: Vec<Channel>,
    viewers: Vec<SyncSender<Outgoing>>,
}

fn lock(state: &Mutex<State>) -> MutexGuard<'_, State> {
    // A viewer thread that panicked leaves consistent data behind (every update is one push
    // or one assignment): go on with it.
    state.lock().unwrap_or_else(|e| e.into_inner())
}

/// A running live-view server; dropping it stops accepting viewers and ends their threads.
#[derive(Debug)]
pub struct LiveServer {
    addr: SocketAddr,
    state: Arc<Mutex<State>>,
    stop: Arc<AtomicBool>,
}

impl LiveServer {
    /// Listens on `addr` (`host:port`; port 0 lets the system choose, see
    /// [`Self::local_addr`]). The error names the address.
    pub fn bind(addr: &str) -> Result<Self, String> {
        let listener =
            TcpListener::bind(addr).map_err(|e| format!("{addr}: cannot listen: {e}"))?;
        let local = listener
            .local_addr()
            .map_err(|e| format!("{addr}: cannot listen: {e}"))?;
        listener
            .set_nonblocking(true)
            .map_err(|e| format!("{addr}: cannot listen: {e}"))?;
        let state = Arc::new(Mutex::new(State::default()));
        let stop = Arc::new(AtomicBool::new(false));
        let (s, st) = (Arc::clone(&state), Arc::clone(&stop));
        thread::Builder::new()
            .name("live-accept".into())
            .spawn(move || accept_loop(listener, s, st))
            .map_err(|e| format!("{addr}: cannot start the server thread: {e}"))?;
        Ok(Self {
            addr: local,
            state,
            stop,
        })
    }

    /// The address the server listens on.
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// Viewers connected now.
    pub fn viewers(&self) -> usize {
        lock(&self.state).viewers.len()
    }

    /// Adds a channel (JSON messages, a JSON schema) and advertises it to the viewers; returns
    /// its id.
    pub fn add_channel(&self, topic: &str, schema_name: &str, schema: &str) -> u32 {
        let mut state = lock(&self.state);
        let id = state.channels.len() as u32 + 1;
        let channel = Channel {
            id,
            topic: topic.to_string(),
            schema_name: schema_name.to_string(),
            schema: schema.to_string(),
            last: None,
        };
        let text = json!({"op": "advertise", "channels": [channel.advertisement()]}).to_string();
        state.channels.push(channel);
        state.viewers.retain(|v| {
            !matches!(
                v.try_send(Outgoing::Advertise(text.clone())),
                Err(TrySendError::Disconnected(_))
            )
        });
        id
    }

    /// Publishes a message of `channel` (an id from [`Self::add_channel`]) logged at `t_ns`.
    pub fn publish(&self, channel: u32, t_ns: u64, data: &[u8]) {
        let data: Arc<[u8]> = Arc::from(data);
        let mut state = lock(&self.state);
        if let Some(c) = state.channels.iter_mut().find(|c| c.id == channel) {
            c.last = Some((t_ns, Arc::clone(&data)));
        }
        state.viewers.retain(|v| {
            !matches!(
                v.try_send(Outgoing::Data {
                    channel,
                    t_ns,
                    data: Arc::clone(&data),
                }),
                Err(TrySendError::Disconnected(_))
            )
        });
    }
}

impl Drop for LiveServer {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        // Dropping the senders ends every viewer's thread at its next look at its queue.
        lock(&self.state).viewers.clear();
    }
}

fn accept_loop(listener: TcpListener, state: Arc<Mutex<State>>, stop: Arc<AtomicBool>) {
    while !stop.load(Ordering::Relaxed) {
        match listener.accept() {
            Ok((stream, peer)) => {
                let s = Arc::clone(&state);
                let spawned = thread::Builder::new()
                    .name("live-viewer".into())
                    .spawn(move || serve_viewer(stream, peer, s));
                if let Err(e) = spawned {
                    debug(&format!("live view: {peer}: no thread for the viewer: {e}"));
                }
            }
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => thread::sleep(POLL),
            Err(e) => {
                debug(&format!("live view: accept: {e}"));
                thread::sleep(POLL);
            }
        }
    }
}

/// A debug-level note (through `tracing` in the onboard build; nowhere otherwise).
fn debug(message: &str) {
    #[cfg(feature = "onboard")]
    tracing::debug!("{message}");
    #[cfg(not(feature = "onboard"))]
    let _ = message;
}

/// The handshake's answer: selects [`SUBPROTOCOL`] when the client offers it.
#[allow(clippy::result_large_err)] // tungstenite's callback signature
fn select_subprotocol(
    request: &Request,
    mut response: Response,
) -> Result<Response, ErrorResponse> {
    let offered = request
        .headers()
        .get_all("Sec-WebSocket-Protocol")
        .iter()
        .filter_map(|v| v.to_str().ok())
        .flat_map(|v| v.split(','))
        .any(|p| p.trim() == SUBPROTOCOL);
    if offered {
        response.headers_mut().insert(
            "Sec-WebSocket-Protocol",
            tungstenite::http::HeaderValue::from_static(SUBPROTOCOL),
        );
    }
    Ok(response)
}

fn serve_viewer(stream: TcpStream, peer: SocketAddr, state: Arc<Mutex<State>>) {
    if let Err(e) = serve_viewer_inner(stream, &state) {
        debug(&format!("live view: {peer}: {e}"));
    }
}

fn serve_viewer_inner(stream: TcpStream, state: &Mutex<State>) -> Result<(), String> {
    stream.set_nonblocking(false).map_err(|e| e.to_string())?;
    stream
        .set_read_timeout(Some(HANDSHAKE_TIMEOUT))
        .map_err(|e| e.to_string())?;
    let _ = stream.set_nodelay(true);
    let mut ws = tungstenite::accept_hdr(stream, select_subprotocol)
        .map_err(|e| format!("handshake: {e}"))?;
    ws.get_ref()
        .set_read_timeout(Some(POLL))
        .map_err(|e| e.to_string())?;
    // Register and take the channels known now under one lock: nothing advertised in between
    // is missed.
    let (rx, channels): (Receiver<Outgoing>, Vec<Value>) = {
        let mut s = lock(state);
        let (tx, rx) = sync_channel(QUEUE_MESSAGES);
        s.viewers.push(tx);
        (rx, s.channels.iter().map(Channel::advertisement).collect())
    };
    let info = json!({
        "op": "serverInfo",
        "name": concat!("papillon ", env!("CARGO_PKG_VERSION")),
        "capabilities": [],
        "supportedEncodings": [],
        "metadata": {},
    });
    send(&mut ws, Message::text(info.to_string()))?;
    send(
        &mut ws,
        Message::text(json!({"op": "advertise", "channels": channels}).to_string()),
    )?;
    // Subscription id by channel id.
    let mut subscriptions: BTreeMap<u32, u32> = BTreeMap::new();
    loop {
        match ws.read() {
            Ok(Message::Text(text)) => {
                for (subscription, channel) in handle_request(text.as_str(), &mut subscriptions) {
                    let last = lock(state)
                        .channels
                        .iter()
                        .find(|c| c.id == channel)
                        .and_then(|c| c.last.clone());
                    if let Some((t_ns, data)) = last {
                        send(&mut ws, message_data(subscription, t_ns, &data))?;
                    }
                }
            }
            Ok(Message::Close(_)) => return Ok(()),
            Ok(_) => {}
            Err(tungstenite::Error::Io(e))
                if matches!(
                    e.kind(),
                    io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut
                ) => {}
            Err(tungstenite::Error::ConnectionClosed | tungstenite::Error::AlreadyClosed) => {
                return Ok(());
            }
            Err(e) => return Err(e.to_string()),
        }
        loop {
            match rx.try_recv() {
                Ok(Outgoing::Advertise(text)) => send(&mut ws, Message::text(text))?,
                Ok(Outgoing::Data {
                    channel,
                    t_ns,
                    data,
                }) => {
                    if let Some(&subscription) = subscriptions.get(&channel) {
                        send(&mut ws, message_data(subscription, t_ns, &data))?;
                    }
                }
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => {
                    // The server was dropped: close politely.
                    let _ = ws.close(None);
                    let _ = ws.flush();
                    return Ok(());
                }
            }
        }
    }
}

fn send(ws: &mut WebSocket<TcpStream>, message: Message) -> Result<(), String> {
    ws.send(message).map_err(|e| e.to_string())
}

/// A binary *message data* frame: opcode 1, subscription id, log time, payload.
fn message_data(subscription: u32, t_ns: u64, data: &[u8]) -> Message {
    let mut bytes = Vec::with_capacity(13 + data.len());
    bytes.push(1);
    bytes.extend_from_slice(&subscription.to_le_bytes());
    bytes.extend_from_slice(&t_ns.to_le_bytes());
    bytes.extend_from_slice(data);
    Message::binary(bytes)
}

/// Applies a client's JSON request to `subscriptions` (subscription id by channel id); returns
/// the (subscription, channel) pairs just subscribed. Anything else is ignored.
fn handle_request(text: &str, subscriptions: &mut BTreeMap<u32, u32>) -> Vec<(u32, u32)> {
    let Ok(request) = serde_json::from_str::<Value>(text) else {
        debug("live view: a client message that is not JSON (ignored)");
        return Vec::new();
    };
    let id = |v: &Value| v.as_u64().and_then(|x| u32::try_from(x).ok());
    let mut added = Vec::new();
    match request["op"].as_str() {
        Some("subscribe") => {
            for s in request["subscriptions"].as_array().into_iter().flatten() {
                if let (Some(subscription), Some(channel)) = (id(&s["id"]), id(&s["channelId"])) {
                    subscriptions.insert(channel, subscription);
                    added.push((subscription, channel));
                }
            }
        }
        Some("unsubscribe") => {
            for s in request["subscriptionIds"].as_array().into_iter().flatten() {
                if let Some(subscription) = id(s) {
                    subscriptions.retain(|_, v| *v != subscription);
                }
            }
        }
        other => debug(&format!(
            "live view: request {other:?} not handled (ignored)"
        )),
    }
    added
}

#[cfg(test)]
mod tests {
    use super::*;
    use tungstenite::client::IntoClientRequest;

    type Client = WebSocket<tungstenite::stream::MaybeTlsStream<TcpStream>>;

    fn connect(server: &LiveServer) -> Client {
        let mut request = format!("ws://{}", server.local_addr())
            .into_client_request()
            .unwrap();
        request.headers_mut().insert(
            "Sec-WebSocket-Protocol",
            tungstenite::http::HeaderValue::from_static(SUBPROTOCOL),
        );
        let (ws, response) = tungstenite::connect(request).unwrap();
        assert_eq!(
            response.headers()["Sec-WebSocket-Protocol"],
            SUBPROTOCOL,
            "the server selects the subprotocol"
        );
        if let tungstenite::stream::MaybeTlsStream::Plain(s) = ws.get_ref() {
            s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
        }
        ws
    }

    fn read_json(ws: &mut Client) -> Value {
        match ws.read().unwrap() {
            Message::Text(t) => serde_json::from_str(t.as_str()).unwrap(),
            other => panic!("expected a JSON message, got {other:?}"),
        }
    }

    #[test]
    fn a_viewer_is_advertised_the_channels_and_gets_what_it_subscribed_to() {
        let server = LiveServer::bind("127.0.0.1:0").unwrap();
        assert_ne!(server.local_addr().port(), 0);
        let map = server.add_channel("/map", "foxglove.Grid", "{}");
        server.publish(map, 5, b"{\"old\":1}");
        server.publish(map, 7, b"{\"latest\":1}");
        let mut ws = connect(&server);
        let info = read_json(&mut ws);
        assert_eq!(info["op"], "serverInfo");
        let ad = read_json(&mut ws);
        assert_eq!(ad["op"], "advertise");
        assert_eq!(ad["channels"][0]["topic"], "/map");
        assert_eq!(ad["channels"][0]["schemaName"], "foxglove.Grid");
        assert_eq!(ad["channels"][0]["encoding"], "json");

        // A channel added later is advertised to the connected viewer.
        let scan = server.add_channel("/scan", "foxglove.LaserScan", "{}");
        let ad = read_json(&mut ws);
        assert_eq!(
            (ad["op"].as_str(), ad["channels"][0]["topic"].as_str()),
            (Some("advertise"), Some("/scan"))
        );
        assert_eq!(ad["channels"][0]["id"], scan);

        ws.send(Message::text(
            json!({"op": "subscribe", "subscriptions": [{"id": 42, "channelId": map}]}).to_string(),
        ))
        .unwrap();
        // The latest map at once, then what is published; the unsubscribed scan never.
        let expect = |ws: &mut Client, t: u64, payload: &[u8]| match ws.read().unwrap() {
            Message::Binary(b) => {
                assert_eq!(b[0], 1, "opcode message data");
                assert_eq!(u32::from_le_bytes(b[1..5].try_into().unwrap()), 42);
                assert_eq!(u64::from_le_bytes(b[5..13].try_into().unwrap()), t);
                assert_eq!(&b[13..], payload);
            }
            other => panic!("expected message data, got {other:?}"),
        };
        expect(&mut ws, 7, b"{\"latest\":1}");
        // Wait until the subscription is registered before publishing again: the latched
        // message came after it.
        server.publish(scan, 8, b"{\"scan\":1}");
        server.publish(map, 9, b"{\"next\":1}");
        expect(&mut ws, 9, b"{\"next\":1}");

        ws.send(Message::text(
            json!({"op": "unsubscribe", "subscriptionIds": [42]}).to_string(),
        ))
        .unwrap();
        // Garbage from a client is ignored, the connection stays.
        ws.send(Message::text("not json")).unwrap();
        ws.send(Message::text(
            json!({"op": "subscribe", "subscriptions": [{"id": 3, "channelId": scan}]}).to_string(),
        ))
        .unwrap();
        // The scan's latest, and nothing of the unsubscribed map.
        match ws.read().unwrap() {
            Message::Binary(b) => {
                assert_eq!(u32::from_le_bytes(b[1..5].try_into().unwrap()), 3);
                assert_eq!(&b[13..], b"{\"scan\":1}");
            }
            other => panic!("{other:?}"),
        }
        server.publish(map, 10, b"{\"unseen\":1}");
        server.publish(scan, 11, b"{\"scan\":2}");
        match ws.read().unwrap() {
            Message::Binary(b) => assert_eq!(&b[13..], b"{\"scan\":2}"),
            other => panic!("{other:?}"),
        }
        assert_eq!(server.viewers(), 1);
        drop(server);
        // The server gone, the viewer's connection is closed.
        loop {
            match ws.read() {
                Ok(Message::Close(_)) | Err(_) => break,
                Ok(_) => {}
            }
        }
    }

    #[test]
    fn an_address_in_use_is_an_error_naming_it() {
        let first = LiveServer::bind("127.0.0.1:0").unwrap();
        let addr = first.local_addr().to_string();
        let e = LiveServer::bind(&addr).unwrap_err();
        assert!(e.starts_with(&addr) && e.contains("cannot listen"), "{e}");
    }
}
