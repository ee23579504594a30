//! Which adapter a run opens, as a scheduler can drive it: `--adapter` by index (`1`), by PCI bus
//! id (`0000:3b:00.0`) or by a substring of the name, among the adapters that
//! `CUDA_VISIBLE_DEVICES` (NVIDIA) and `ROCR_VISIBLE_DEVICES` (AMD) leave visible; Vulkan ignores
//! both variables, so ricochet applies them itself. Pure functions of a list of adapter
//! descriptions ([`Candidate`]), unit-tested on synthetic lists; [`super::GpuContext::new`] applies
//! them to the adapters wgpu enumerates. Host-side only, no GPU twin.
//!
//! The list ([`arrange`]): the adapters by kind (discrete, integrated, virtual, CPU, other), then
//! by PCI bus id, then by name. A visibility variable lists indices into its vendor's adapters
//! in PCI bus order (the order of `nvidia-smi` and of the `/dev/nvidiaN` minor numbers that Slurm's
//! GPU indices follow; CUDA's own default order is fastest-first unless
//! `CUDA_DEVICE_ORDER=PCI_BUS_ID`): those adapters stay, in the variable's order (`2,0` makes the
//! third NVIDIA adapter the first), and that vendor's others are dropped; an empty variable hides
//! every adapter of its vendor, and parsing stops at the first entry that is not an index of one
//! (as CUDA's does: `0,2,-1,1` is `0,2`). Entries that are UUIDs (`GPU-...`, `MIG-...`) cannot be
//! mapped: Vulkan adapters do not report them through wgpu; they are refused, naming the variable,
//! rather than guessed. The index of `--adapter N` is the position in the list that remains.

use std::fmt;

/// PCI vendor id of NVIDIA.
pub const NVIDIA: u32 = 0x10de;
/// PCI vendor id of AMD.
pub const AMD: u32 = 0x1002;

/// The kind of an adapter, best first.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Kind {
    /// A discrete GPU.
    Discrete,
    /// A GPU integrated with the CPU.
    Integrated,
    /// A virtual GPU.
    Virtual,
    /// A software implementation on the CPU (Mesa lavapipe).
    Cpu,
    /// Anything else.
    Other,
}

impl From<wgpu::DeviceType> for Kind {
    fn from(t: wgpu::DeviceType) -> Self {
        match t {
            wgpu::DeviceType::DiscreteGpu => Kind::Discrete,
            wgpu::DeviceType::IntegratedGpu => Kind::Integrated,
            wgpu::DeviceType::VirtualGpu => Kind::Virtual,
            wgpu::DeviceType::Cpu => Kind::Cpu,
            wgpu::DeviceType::Other => Kind::Other,
        }
    }
}

/// What the choice knows of an adapter.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Candidate {
    /// Its name (`NVIDIA H100 80GB HBM3`, `llvmpipe (LLVM 15.0.6, 256 bits)`).
    pub name: String,
    /// Its PCI vendor id ([`NVIDIA`], [`AMD`], ...).
    pub vendor: u32,
    /// Its PCI bus id as wgpu reports it (`0000:3b:00.0`; empty when unknown).
    pub pci_bus_id: String,
    /// Its kind.
    pub kind: Kind,
}

impl From<&wgpu::AdapterInfo> for Candidate {
    fn from(info: &wgpu::AdapterInfo) -> Self {
        Self {
            name: info.name.clone(),
            vendor: info.vendor,
            pci_bus_id: info.device_pci_bus_id.clone(),
            kind: info.device_type.into(),
        }
    }
}

/// How `--adapter` names an adapter.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Selector {
    /// Its position in the list (`--adapter 1`).
    Index(usize),
    /// Its PCI bus id, normalised to `dddd:bb:dd.f` in lower case (`--adapter 0000:3B:00.0`,
    /// `--adapter 3b:00.0`, `--adapter 00000000:3B:00.0` as `nvidia-smi` writes it).
    PciBusId(String),
    /// A substring of its name, case-insensitive (`--adapter h100`).
    Name(String),
}

impl Selector {
    /// Reads `--adapter`: digits are an index, a PCI bus id (`[domain:]bus:device.function`, hex)
    /// is a bus id, anything else a name.
    pub fn parse(text: &str) -> Self {
        let t = text.trim();
        if !t.is_empty() && t.chars().all(|c| c.is_ascii_digit()) {
            if let Ok(i) = t.parse() {
                return Selector::Index(i);
            }
        }
        match normalise_bus_id(t) {
            Some(id) => Selector::PciBusId(id),
            None => Selector::Name(t.to_string()),
        }
    }
}

impl fmt::Display for Selector {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Selector::Index(i) => write!(f, "index {i}"),
            Selector::PciBusId(id) => write!(f, "PCI bus id {id}"),
            Selector::Name(n) => write!(f, "{n:?}"),
        }
    }
}

/// A PCI bus id as `dddd:bb:dd.f` (lower case, 4-digit domain), or `None` when `text` is not one.
pub fn normalise_bus_id(text: &str) -> Option<String> {
    let t = text.trim();
    let (domain, rest) = match t.matches(':').count() {
        2 => {
            let (d, r) = t.split_once(':')?;
            (u32::from_str_radix(d, 16).ok()?, r)
        }
        1 => (0, t),
        _ => return None,
    };
    let (bus, rest) = rest.split_once(':')?;
    let (device, function) = rest.split_once('.')?;
    let hex = |s: &str, max: usize| {
        (!s.is_empty() && s.len() <= max && s.chars().all(|c| c.is_ascii_hexdigit()))
            .then(|| u32::from_str_radix(s, 16).ok())
            .flatten()
    };
    let (bus, device, function) = (hex(bus, 2)?, hex(device, 2)?, hex(function, 1)?);
    (device < 32 && function < 8).then(|| format!("{domain:04x}:{bus:02x}:{device:02x}.{function}"))
}

/// The visibility variables of the environment.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Visible {
    /// `CUDA_VISIBLE_DEVICES`, when set.
    pub cuda: Option<String>,
    /// `ROCR_VISIBLE_DEVICES`, when set.
    pub rocr: Option<String>,
}

impl Visible {
    /// The variables of this process's environment.
    pub fn from_env() -> Self {
        Self {
            cuda: std::env::var("CUDA_VISIBLE_DEVICES").ok(),
            rocr: std::env::var("ROCR_VISIBLE_DEVICES").ok(),
        }
    }

    /// The variable for `vendor` (name, value), when set.
    fn of(&self, vendor: u32) -> Option<(&'static str, &str)> {
        match vendor {
            NVIDIA => self.cuda.as_deref().map(|v| ("CUDA_VISIBLE_DEVICES", v)),
            AMD => self.rocr.as_deref().map(|v| ("ROCR_VISIBLE_DEVICES", v)),
            _ => None,
        }
    }
}

/// The adapters of `candidates` a run may open, as indices into `candidates`, in the order of the
/// list (see the module's documentation): sorted by kind, PCI bus id and name, with each
/// vendor whose visibility variable is set restricted to (and ordered by) the variable's entries.
///
/// # Errors
/// A message naming the variable when it holds a UUID (`GPU-...`, `MIG-...`), which cannot be
/// mapped to an adapter.
pub fn arrange(candidates: &[Candidate], visible: &Visible) -> Result<Vec<usize>, String> {
    let mut order: Vec<usize> = (0..candidates.len()).collect();
    order.sort_by(|&a, &b| {
        let (a, b) = (&candidates[a], &candidates[b]);
        (a.kind, &a.pci_bus_id, &a.name).cmp(&(b.kind, &b.pci_bus_id, &b.name))
    });
    for vendor in [NVIDIA, AMD] {
        let Some((variable, value)) = visible.of(vendor) else {
            continue;
        };
        // The vendor's adapters in PCI bus order, and their slots in the list.
        let mut by_bus: Vec<usize> = order
            .iter()
            .copied()
            .filter(|&i| candidates[i].vendor == vendor)
            .collect();
        by_bus.sort_by(|&a, &b| {
            (&candidates[a].pci_bus_id, &candidates[a].name)
                .cmp(&(&candidates[b].pci_bus_id, &candidates[b].name))
        });
        let mut kept: Vec<usize> = Vec::new();
        for entry in value.split(',').map(str::trim) {
            if entry.starts_with("GPU-") || entry.starts_with("MIG-") {
                return Err(format!(
                    "{variable}={value}: {entry:?} is a UUID, which cannot be mapped to a Vulkan \
                     adapter (wgpu does not report UUIDs); set the variable to indices (as Slurm \
                     does), or choose the adapter with --adapter and its PCI bus id"
                ));
            }
            match entry.parse::<usize>().ok().and_then(|k| by_bus.get(k)) {
                Some(&i) if !kept.contains(&i) => kept.push(i),
                // CUDA stops at the first entry that is not a device index.
                _ => break,
            }
        }
        let slots: Vec<usize> = order
            .iter()
            .enumerate()
            .filter(|(_, &i)| candidates[i].vendor == vendor)
            .map(|(s, _)| s)
            .collect();
        // The kept adapters take the vendor's first slots, in the variable's order; the rest go.
        let mut next = kept.iter();
        let mut arranged = Vec::with_capacity(order.len());
        for (s, &i) in order.iter().enumerate() {
            if slots.contains(&s) {
                if let Some(&k) = next.next() {
                    arranged.push(k);
                }
            } else {
                arranged.push(i);
            }
        }
        order = arranged;
    }
    Ok(order)
}

/// The adapter of `candidates` (its index there) that `selector` names among those [`arrange`]
/// leaves, or the first of those (the best kind) without a selector.
///
/// # Errors
/// A message listing the adapters (with their indices and bus ids) when none is left or none
/// matches, and [`arrange`]'s.
pub fn choose(
    candidates: &[Candidate],
    selector: Option<&Selector>,
    visible: &Visible,
) -> Result<usize, String> {
    let order = arrange(candidates, visible)?;
    let listed = || listing(candidates, &order);
    let hidden = if order.len() < candidates.len() {
        format!(
            " ({} hidden by {})",
            candidates.len() - order.len(),
            [
                visible
                    .cuda
                    .as_ref()
                    .map(|v| format!("CUDA_VISIBLE_DEVICES={v}")),
                visible
                    .rocr
                    .as_ref()
                    .map(|v| format!("ROCR_VISIBLE_DEVICES={v}")),
            ]
            .into_iter()
            .flatten()
            .collect::<Vec<_>>()
            .join(" and ")
        )
    } else {
        String::new()
    };
    let found = match selector {
        None => order.first().copied(),
        Some(Selector::Index(k)) => order.get(*k).copied(),
        Some(Selector::PciBusId(id)) => order
            .iter()
            .copied()
            .find(|&i| normalise_bus_id(&candidates[i].pci_bus_id).as_deref() == Some(id)),
        Some(Selector::Name(n)) => order.iter().copied().find(|&i| {
            candidates[i]
                .name
                .to_lowercase()
                .contains(&n.to_lowercase())
        }),
    };
    found.ok_or_else(|| match selector {
        None if candidates.is_empty() => "no GPU adapter found (install a Vulkan driver, e.g. \
                                          Mesa lavapipe: apt-get install mesa-vulkan-drivers)"
            .to_string(),
        None => format!("no GPU adapter left{hidden}; found: {}", listed()),
        Some(s) => format!("no GPU adapter matches {s}{hidden}; found: {}", listed()),
    })
}

/// The adapters of `order` as `[0] name (bus id), [1] ...`.
pub fn listing(candidates: &[Candidate], order: &[usize]) -> String {
    let items: Vec<String> = order
        .iter()
        .enumerate()
        .map(|(k, &i)| {
            let c = &candidates[i];
            if c.pci_bus_id.is_empty() {
                format!("[{k}] {} ({:?})", c.name, c.kind)
            } else {
                format!("[{k}] {} ({:?}, {})", c.name, c.kind, c.pci_bus_id)
            }
        })
        .collect();
    if items.is_empty() {
        "none".into()
    } else {
        items.join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gpu(name: &str, vendor: u32, bus: &str, kind: Kind) -> Candidate {
        Candidate {
            name: name.into(),
            vendor,
            pci_bus_id: bus.into(),
            kind,
        }
    }

    /// Four H100s enumerated out of bus order, an AMD card, and lavapipe.
    fn node() -> Vec<Candidate> {
        vec![
            gpu("llvmpipe (LLVM 15)", 0x10005, "", Kind::Cpu),
            gpu("NVIDIA H100 c", NVIDIA, "0000:9b:00.0", Kind::Discrete),
            gpu("NVIDIA H100 a", NVIDIA, "0000:1b:00.0", Kind::Discrete),
            gpu("AMD MI210", AMD, "0000:c1:00.0", Kind::Discrete),
            gpu("NVIDIA H100 d", NVIDIA, "0000:bb:00.0", Kind::Discrete),
            gpu("NVIDIA H100 b", NVIDIA, "0000:3b:00.0", Kind::Discrete),
        ]
    }

    fn names(c: &[Candidate], order: &[usize]) -> Vec<String> {
        order.iter().map(|&i| c[i].name.clone()).collect()
    }

    fn env(cuda: Option<&str>, rocr: Option<&str>) -> Visible {
        Visible {
            cuda: cuda.map(str::to_string),
            rocr: rocr.map(str::to_string),
        }
    }

    #[test]
    fn selectors_parse_as_index_bus_id_or_name() {
        assert_eq!(Selector::parse("1"), Selector::Index(1));
        assert_eq!(
            Selector::parse("0000:3B:00.0"),
            Selector::PciBusId("0000:3b:00.0".into())
        );
        assert_eq!(
            Selector::parse("3b:00.0"),
            Selector::PciBusId("0000:3b:00.0".into())
        );
        assert_eq!(
            Selector::parse("00000000:3B:00.0"),
            Selector::PciBusId("0000:3b:00.0".into())
        );
        assert_eq!(Selector::parse("h100"), Selector::Name("h100".into()));
        assert_eq!(
            Selector::parse("llvmpipe"),
            Selector::Name("llvmpipe".into())
        );
        assert_eq!(normalise_bus_id("3b:00.9"), None);
        assert_eq!(normalise_bus_id("3b:40.0"), None);
    }

    #[test]
    fn the_list_is_by_kind_then_bus_id() {
        let c = node();
        let order = arrange(&c, &Visible::default()).unwrap();
        assert_eq!(
            names(&c, &order),
            [
                "NVIDIA H100 a",
                "NVIDIA H100 b",
                "NVIDIA H100 c",
                "NVIDIA H100 d",
                "AMD MI210",
                "llvmpipe (LLVM 15)"
            ]
        );
        let no = Visible::default();
        assert_eq!(c[choose(&c, None, &no).unwrap()].name, "NVIDIA H100 a");
        let pick = |s: &str| {
            c[choose(&c, Some(&Selector::parse(s)), &no).unwrap()]
                .name
                .clone()
        };
        assert_eq!(pick("1"), "NVIDIA H100 b");
        assert_eq!(pick("5"), "llvmpipe (LLVM 15)");
        assert_eq!(pick("0000:9B:00.0"), "NVIDIA H100 c");
        assert_eq!(pick("mi210"), "AMD MI210");
        let e = choose(&c, Some(&Selector::parse("6")), &no).unwrap_err();
        assert!(e.contains("index 6") && e.contains("[5] llvmpipe"), "{e}");
        let e = choose(&c, Some(&Selector::parse("0000:01:00.0")), &no).unwrap_err();
        assert!(
            e.contains("0000:01:00.0") && e.contains("0000:3b:00.0"),
            "{e}"
        );
    }

    #[test]
    fn cuda_visible_devices_restricts_and_orders_the_nvidia_adapters_by_bus_order() {
        let c = node();
        // Slurm gives a task the GPU of index 2 (the third in bus order).
        let v = env(Some("2"), None);
        let order = arrange(&c, &v).unwrap();
        assert_eq!(
            names(&c, &order),
            ["NVIDIA H100 c", "AMD MI210", "llvmpipe (LLVM 15)"]
        );
        assert_eq!(c[choose(&c, None, &v).unwrap()].name, "NVIDIA H100 c");
        assert_eq!(
            c[choose(&c, Some(&Selector::Index(0)), &v).unwrap()].name,
            "NVIDIA H100 c"
        );
        // The variable's order; parsing stops at the first entry that is not an index.
        let v = env(Some("3,0,-1,1"), None);
        assert_eq!(
            names(&c, &arrange(&c, &v).unwrap()),
            [
                "NVIDIA H100 d",
                "NVIDIA H100 a",
                "AMD MI210",
                "llvmpipe (LLVM 15)"
            ]
        );
        // Empty: no NVIDIA adapter; an index past the end stops there.
        for value in ["", "7", "NoDevFiles"] {
            let v = env(Some(value), None);
            assert_eq!(
                names(&c, &arrange(&c, &v).unwrap()),
                ["AMD MI210", "llvmpipe (LLVM 15)"],
                "{value:?}"
            );
        }
        // A bus id outside the visible set is not found, and the message says why.
        let v = env(Some("0"), None);
        let e = choose(&c, Some(&Selector::parse("0000:9b:00.0")), &v).unwrap_err();
        assert!(e.contains("3 hidden by CUDA_VISIBLE_DEVICES=0"), "{e}");
    }

    #[test]
    fn rocr_visible_devices_restricts_the_amd_adapters_and_uuids_are_refused() {
        let c = node();
        let v = env(None, Some(""));
        assert!(!names(&c, &arrange(&c, &v).unwrap()).contains(&"AMD MI210".to_string()));
        let v = env(None, Some("0"));
        assert!(names(&c, &arrange(&c, &v).unwrap()).contains(&"AMD MI210".to_string()));
        for uuid in ["GPU-8f5e1a2b-0000-1111-2222-333344445555", "MIG-abc"] {
            let v = env(Some(uuid), None);
            let e = arrange(&c, &v).unwrap_err();
            assert!(
                e.contains("CUDA_VISIBLE_DEVICES") && e.contains("UUID"),
                "{e}"
            );
        }
        let none: Vec<Candidate> = Vec::new();
        assert!(choose(&none, None, &Visible::default())
            .unwrap_err()
            .contains("no GPU adapter found"));
    }
}
