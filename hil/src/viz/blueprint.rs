//! The layout the viewer opens on: the rig and arm in 2D with the ellipses and the event log
//! under it, position and force plots beside it, the other series in tabs.
//!
//! rerun's Rust blueprint API (`rerun::blueprint::Blueprint`) names views and containers by
//! random UUIDs and stamps rows with the wall clock, so a file holding its output is never the
//! same twice. This module writes the same archetypes (`ViewBlueprint`, `ViewContents`,
//! `ContainerBlueprint`, `ViewportBlueprint`, `TimePanelBlueprint`) with UUIDs hashed from the
//! view names, which keeps saved files reproducible.

use rerun::external::re_log_types::{BlueprintActivationCommand, LogMsg, StoreId, StoreKind};
use rerun::external::re_sdk_types::blueprint::archetypes::{
    ContainerBlueprint, TimePanelBlueprint, ViewBlueprint, ViewContents, ViewportBlueprint,
};
use rerun::external::re_sdk_types::blueprint::components::{
    AutoLayout, AutoViews, ColumnShare, ContainerKind, IncludedContent, QueryExpression,
    RootContainer, RowShare, TimelineName, ViewClass,
};
use rerun::external::re_sdk_types::components::Name;
use rerun::external::re_sdk_types::datatypes::{Bool, Float32, Uuid};
use rerun::log::{Chunk, RowId};
use rerun::{AsComponents, TimePoint, Timeline};
use sha2::{Digest as _, Sha256};

use super::ids::IdSource;
use super::{VizError, paths};

/// A node of the layout tree.
enum Node {
    View {
        name: &'static str,
        class: &'static str,
        origin: &'static str,
        contents: &'static [&'static str],
    },
    Container {
        name: &'static str,
        kind: ContainerKind,
        shares: &'static [f32],
        children: Vec<Node>,
    },
}

fn view(
    name: &'static str,
    class: &'static str,
    origin: &'static str,
    contents: &'static [&'static str],
) -> Node {
    Node::View {
        name,
        class,
        origin,
        contents,
    }
}

fn series(name: &'static str, origin: &'static str) -> Node {
    view(name, "TimeSeries", origin, &["$origin/**"])
}

/// A time-series view that also holds the overlays of its channels (`contents`: the
/// origin's and the `measured/`, `simulated/` or `predicted/` copies of it), so measured
/// and simulated curves share one plot.
fn overlaid(name: &'static str, origin: &'static str, contents: &'static [&'static str]) -> Node {
    view(name, "TimeSeries", origin, contents)
}

fn container(
    name: &'static str,
    kind: ContainerKind,
    shares: &'static [f32],
    children: Vec<Node>,
) -> Node {
    Node::Container {
        name,
        kind,
        shares,
        children,
    }
}

/// The layout.
fn layout() -> Node {
    let scene = view(
        "Rig and arm",
        "2D",
        paths::SCENE,
        &["/rig/**", "/arm/**", "/trial/**", "/ellipses/**"],
    );
    let ellipses = view(
        "Impedance ellipses",
        "2D",
        paths::SCENE,
        &["/ellipses/**", "/trial/path", "/rig/carriage"],
    );
    let events = view("Events", "TextLog", "/events", &["$origin/**"]);
    let left = container(
        "Scene",
        ContainerKind::Vertical,
        &[2.0, 1.0],
        vec![
            scene,
            container(
                "Ellipses and events",
                ContainerKind::Horizontal,
                &[1.0, 1.0],
                vec![ellipses, events],
            ),
        ],
    );
    let right = container(
        "Signals",
        ContainerKind::Vertical,
        &[1.0, 1.0, 1.0],
        vec![
            overlaid(
                "Position (m)",
                "/plots/position",
                &[
                    "$origin/**",
                    "/measured/plots/position/**",
                    "/simulated/plots/position/**",
                ],
            ),
            overlaid(
                "Force (N)",
                "/plots/force",
                &[
                    "$origin/**",
                    "/measured/plots/force/**",
                    "/simulated/plots/force/**",
                ],
            ),
            container(
                "More signals",
                ContainerKind::Tabs,
                &[],
                vec![
                    overlaid(
                        "Velocity (m/s)",
                        "/plots/velocity",
                        &[
                            "$origin/**",
                            "/measured/plots/velocity/**",
                            "/simulated/plots/velocity/**",
                        ],
                    ),
                    series("Reference (m)", "/plots/reference"),
                    overlaid(
                        "Command (N)",
                        "/plots/command",
                        &[
                            "$origin/**",
                            "/measured/plots/command/**",
                            "/simulated/plots/command/**",
                            "/predicted/plots/command/**",
                        ],
                    ),
                    series("Arm angles (deg)", "/plots/arm"),
                    series("Muscle activations (N)", "/plots/muscles"),
                    series("Wake-up latency (µs)", "/plots/timing/wake_latency_us"),
                    series("Held ticks (share)", "/plots/timing/held"),
                    series("Response (mm)", "/plots/response"),
                ],
            ),
        ],
    );
    container(
        "rigtwin",
        ContainerKind::Horizontal,
        &[1.2, 1.0],
        vec![left, right],
    )
}

/// A UUID that is a function of the name (version-4 layout, so it looks like any other).
fn uuid_of(name: &str) -> [u8; 16] {
    let digest = Sha256::digest(format!("rigtwin blueprint/{name}").as_bytes());
    let mut bytes = [0u8; 16];
    bytes.copy_from_slice(&digest[..16]);
    bytes[6] = (bytes[6] & 0x0f) | 0x40;
    bytes[8] = (bytes[8] & 0x3f) | 0x80;
    bytes
}

/// The hyphenated form rerun uses in blueprint entity paths.
fn hyphenated(bytes: [u8; 16]) -> String {
    let hex: String = bytes.iter().map(|b| format!("{b:02x}")).collect();
    format!(
        "{}-{}-{}-{}-{}",
        &hex[0..8],
        &hex[8..12],
        &hex[12..16],
        &hex[16..20],
        &hex[20..32]
    )
}

fn node_path(node: &Node) -> String {
    match node {
        Node::View { name, .. } => format!("view/{}", hyphenated(uuid_of(name))),
        Node::Container { name, .. } => format!("container/{}", hyphenated(uuid_of(name))),
    }
}

struct Writer<'a> {
    ids: &'a mut IdSource,
    chunks: Vec<Chunk>,
}

impl Writer<'_> {
    fn row(&mut self, path: &str, arch: &dyn AsComponents) -> Result<(), VizError> {
        let id = self.ids.chunk();
        let timepoint = TimePoint::from([(Timeline::new_sequence("blueprint"), 0)]);
        let chunk = Chunk::builder_with_id(id, path)
            .with_archetype(RowId::from_tuid(id.as_tuid().next()), timepoint, arch)
            .build()
            .map_err(|source| VizError::Chunk {
                entity: path.to_owned(),
                source,
            })?;
        self.chunks.push(chunk);
        Ok(())
    }

    fn node(&mut self, node: &Node) -> Result<(), VizError> {
        let path = node_path(node);
        match node {
            Node::View {
                name,
                class,
                origin,
                contents,
            } => {
                let queries = contents.iter().map(|q| QueryExpression((*q).into()));
                self.row(&format!("{path}/ViewContents"), &ViewContents::new(queries))?;
                let arch = ViewBlueprint::new(ViewClass((*class).into()))
                    .with_display_name(Name((*name).into()))
                    .with_space_origin(origin.to_string());
                self.row(&path, &arch)
            }
            Node::Container {
                name,
                kind,
                shares,
                children,
            } => {
                for child in children {
                    self.node(child)?;
                }
                let included: Vec<IncludedContent> = children
                    .iter()
                    .map(|c| IncludedContent(node_path(c).into()))
                    .collect();
                let mut arch = ContainerBlueprint::new(*kind)
                    .with_display_name(Name((*name).into()))
                    .with_contents(included);
                let shares = shares.iter().map(|&s| Float32(s));
                arch = match kind {
                    ContainerKind::Horizontal => {
                        arch.with_col_shares(shares.map(ColumnShare).collect::<Vec<_>>())
                    }
                    ContainerKind::Vertical => {
                        arch.with_row_shares(shares.map(RowShare).collect::<Vec<_>>())
                    }
                    _ => arch,
                };
                self.row(&path, &arch)
            }
        }
    }
}

/// The blueprint store's messages and the command that activates it.
pub(crate) fn messages(
    recording: &StoreId,
    ids: &mut IdSource,
) -> Result<(Vec<LogMsg>, BlueprintActivationCommand), VizError> {
    let store_id = StoreId::new(
        StoreKind::Blueprint,
        recording.application_id().clone(),
        format!("{}-blueprint", recording.recording_id().as_str()),
    );
    let mut writer = Writer {
        ids,
        chunks: Vec::new(),
    };
    let root = layout();
    writer.node(&root)?;
    let root_id = Uuid {
        bytes: uuid_of(match &root {
            Node::View { name, .. } | Node::Container { name, .. } => name,
        }),
    };
    let viewport = ViewportBlueprint::new()
        .with_root_container(RootContainer(root_id))
        .with_auto_layout(AutoLayout(Bool(false)))
        .with_auto_views(AutoViews(Bool(false)));
    writer.row("viewport", &viewport)?;
    let time_panel = TimePanelBlueprint::new().with_timeline(TimelineName("time".into()));
    writer.row("time_panel", &time_panel)?;

    let info_row = writer.ids.message();
    let mut msgs = vec![LogMsg::SetStoreInfo(
        rerun::external::re_log_types::SetStoreInfo {
            row_id: *info_row,
            info: rerun::external::re_log_types::StoreInfo::new(
                store_id.clone(),
                super::sink::store_source(),
            ),
        },
    )];
    for chunk in writer.chunks {
        let entity = chunk.entity_path().to_string();
        let arrow = chunk
            .to_arrow_msg()
            .map_err(|source| VizError::Chunk { entity, source })?;
        msgs.push(LogMsg::ArrowMsg(store_id.clone(), arrow));
    }
    let activation = BlueprintActivationCommand {
        blueprint_id: store_id,
        make_active: true,
        make_default: true,
    };
    Ok((msgs, activation))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uuids_are_stable_and_hyphenated_like_rerun() {
        let a = hyphenated(uuid_of("Rig and arm"));
        assert_eq!(a, hyphenated(uuid_of("Rig and arm")));
        assert_ne!(a, hyphenated(uuid_of("Force (N)")));
        assert_eq!(a.len(), 36);
        assert_eq!(a.as_bytes()[14], b'4');
    }
}
