//! How a scene's contact stage is solved and dispatched on the device: the choices a caller may
//! make ([`ContactOptions`]) and the path taken (`Path`), decided by adapter and size where not
//! asked for ([`super::solve::multi_path`], [`super::solve::split_path`],
//! [`super::one::one_path`], [`one_group`]). The CPU reference has one path
//! ([`crate::contact::ContactSet::apply`]); every device path gives its results within the
//! solve's accuracy of it, and the paths that differ only in their dispatches the same bits.

use crate::error::{Error, Result};

use super::{one, search, solve};

/// Choices of the contact stage a caller may make (tests, benchmarks); the defaults decide by
/// adapter and size.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ContactOptions {
    /// The per-colour solve path (`Some(true)`) or one workgroup (`Some(false)`); `None`:
    /// [`solve::multi_path`].
    pub multi: Option<bool>,
    /// On the one-workgroup path, the active-set re-checks as their own dispatches over many
    /// workgroups (`Some(true)`) or inside the solve's workgroup (`Some(false)`); `None`:
    /// [`solve::split_path`]. The same constraints and arithmetic either way: the same bits on
    /// lavapipe. On an H100 the two kernels round apart, the sweeps then stop in other sweeps,
    /// and the striker test's displacements differ by 1.5e-7 m: about as far as either path
    /// lies from the f64 CPU reference.
    pub split: Option<bool>,
    /// The contact stage in one workgroup before the search and one after it (`Some(true)`;
    /// the one-workgroup solve with its re-checks inside), or the per-item kernels
    /// (`Some(false)`); `None`: [`one::one_path`] where neither `multi` nor `split` is asked
    /// for. The same bits either way.
    pub one: Option<bool>,
    /// Plain projected Gauss-Seidel sweeps on the one-workgroup path (`true`) instead of the
    /// extrapolated ones (the default, as on the CPU reference); for comparisons.
    pub plain_sweeps: bool,
    /// 2 x 2 blocks in the one-workgroup solve (`Some(true)`): the two constraints of a node
    /// pair met from both passes solved together, as on the CPU reference (`contact_colour.wgsl`
    /// `pair_constraints`, `contact_solve.wgsl` `block_packed`), or each on its own
    /// (`Some(false)`); `None`: [`pair_blocks`]. The bench striker's sweeps a step go 15.4 -> 6.1
    /// (10^4 elements) and 28.5 -> 10.6 (10^5) with them, on any adapter.
    pub pair_blocks: Option<bool>,
    /// Whether the one-workgroup solve's sweeps keep the packed nodes' records (dv, 1/m) and the
    /// multipliers in workgroup memory, in the compaction's arrays, free after it, where they fit
    /// (`Some(true)`), or read and write them through storage (`Some(false)`); `None`:
    /// [`local_sweeps`]. The same bits either way.
    pub local_sweeps: Option<bool>,
    /// Initial candidate capacity (words); `None`: 4 per slot, at least 1024. A search that
    /// needs more grows the buffer.
    pub candidate_capacity: Option<u32>,
    /// Threads of the one-workgroup contact kernels (the search's scans, the one-workgroup
    /// solve, the reports' end), a power of two from 8 to the adapter's largest workgroup (at
    /// most 1024); `None`: [`one_group`]. Every
    /// size gives the same node bits (their sums are of integers, or per constraint within a
    /// colour); only the reports' float sums change order.
    pub group: Option<u32>,
    /// Lagrange constraints the one-workgroup solve compacts in workgroup memory, at most
    /// [`super::local_constraints`] of the device (`Some(0)`: every compaction through storage);
    /// `None`: [`super::local_constraints`]. The same bits at every size.
    pub compact_local: Option<u32>,
    /// Whether the one-workgroup solve colours its constraints in parallel rounds in a hashed
    /// order (`true`) or greedily in slot order in one invocation (`false`); `None`:
    /// [`parallel_colouring`]. Each gives the same bits at every size and on every run.
    pub parallel_colouring: Option<bool>,
    /// The search in one workgroup, one dispatch that is empty on the steps that do not search
    /// (`Some(true)`), or its eleven per-item kernels, dispatched indirectly and empty on those
    /// steps (`Some(false)`); `None`: [`super::search::search_one_path`]. Not with the
    /// per-colour solve. The same bits either way.
    pub search_one: Option<bool>,
    /// How the search switches between its two ways by the rate of the searches
    /// ([`SearchSwitch`]); `None`: [`search::search_switch`] (on GPUs, for contact sets between
    /// [`search::SEARCH_ONE_ITEMS`] and [`search::SEARCH_ONE_RARE_ITEMS`] nodes and slots). Not
    /// with `search_one` set. The same bits either way.
    pub search_switch: Option<SearchSwitch>,
}

impl Default for ContactOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl ContactOptions {
    /// The defaults ([`Default`]), as a constant: `ContactOptions { multi: Some(true),
    /// ..ContactOptions::DEFAULT }` in a `const`.
    pub const DEFAULT: Self = Self {
        multi: None,
        split: None,
        one: None,
        plain_sweeps: false,
        pair_blocks: None,
        local_sweeps: None,
        candidate_capacity: None,
        group: None,
        compact_local: None,
        parallel_colouring: None,
        search_one: None,
        search_switch: None,
    };
}

/// The search's switch between its per-item kernels, which cost their empty dispatches on every
/// step that does not search, and one workgroup, which costs more on the steps that do: over each
/// `window` steps (or the first readback after them) the host counts the searches, and the next
/// steps search in one workgroup when they were fewer than `searches` in `window` steps, else per
/// item. Both ways give the same bits (tested), so the switch changes only the time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SearchSwitch {
    /// Steps over which the searches are counted (at least 1).
    pub window: u32,
    /// Searches in `window` steps below which the search runs in one workgroup.
    pub searches: u32,
}

/// Whether the one-workgroup solve colours in parallel rounds on an adapter of `device_type`:
/// on GPUs, not on CPU adapters. On lavapipe the rounds cost more than the one invocation's
/// loop: the striker ran 5-11 % fewer steps a second (10^4 and 10^5 elements, 2026-11-28), with
/// 7-12 % more sweeps in the hashed order than in slot order.
pub fn parallel_colouring(device_type: wgpu::DeviceType) -> bool {
    device_type != wgpu::DeviceType::Cpu
}

/// Whether the one-workgroup solve sweeps the node pairs met from both passes as 2 x 2 blocks
/// on an adapter of `device_type` ([`ContactOptions::pair_blocks`]): on GPUs, not on CPU
/// adapters. The blocks cut the sweeps on every adapter (the bench striker 15.4 -> 6.1 sweeps a
/// step at 10^4 elements, 28.5 -> 10.6 at 10^5, lavapipe, 2026-11-29), and the GPUs' solve is
/// bound by its sweeps (the striker's at 10^5: 211 us a step in 28 sweeps on an NVIDIA H200,
/// 2026-11-28). On lavapipe the pairing costs more than the sweeps it saves: the 10^5 striker's
/// one-workgroup contact stage took 1 466-1 499 us a step with them against 1 302-1 355 without
/// (2026-11-29).
pub fn pair_blocks(device_type: wgpu::DeviceType) -> bool {
    device_type != wgpu::DeviceType::Cpu
}

/// Whether the one-workgroup solve's sweeps keep their state in workgroup memory on an adapter of
/// `device_type` ([`ContactOptions::local_sweeps`]): on GPUs, where the colours of a sweep then
/// wait on workgroup barriers and workgroup memory instead of on storage, not on CPU adapters.
/// On lavapipe workgroup memory is no faster than storage and the branches cost: the bench
/// striker's contact stage took 1.22-1.31 ms a step at 10^5 elements with it against
/// 0.99-1.10 ms without (2026-11-28).
pub fn local_sweeps(device_type: wgpu::DeviceType) -> bool {
    device_type != wgpu::DeviceType::Cpu
}

/// Threads of the one-workgroup contact kernels on an adapter of `device_type`: 256 on GPUs, 8
/// on CPU adapters. On lavapipe one workgroup runs on one core in lane groups of 8, and each
/// barrier of a larger group switches between them: the 10^5-element striker's solve took
/// 1.78 ms a step with 64 threads, 1.24 ms with 8 (BENCHMARKS.md, 2026-11-24, dd3f611).
pub fn one_group(device_type: wgpu::DeviceType) -> u32 {
    if device_type == wgpu::DeviceType::Cpu {
        8
    } else {
        256
    }
}

// `local_constraints` (in `shader`, whose `Features` default needs it) reserves room for the
// per-item kernels' workgroups of this many threads.
const _: () = assert!(super::CG == crate::gpu::shader::ITEM_GROUP);

/// The most contact slots or nodes the contact stage takes on a CPU adapter: 2^18. Beyond it
/// lavapipe's search (Mesa 22.3.6) wrote wrong candidate offsets on 2026-11-28, whatever the
/// segments: the bench striker with failure (every node of both bodies a slot) found its
/// candidates at 241 602 slots (n = 200) and lost them at 377 002 (n = 250) and 543 000 (n = 300),
/// as a hash grid of 2^19 buckets lost them where 2^18 did not ([`super::MAX_BUCKETS`]). The likely
/// cause (2026-11-28): llvmpipe ends a shader invocation's loops after 65 535 iterations in all
/// (Mesa's `LP_MAX_TGSI_LOOP_ITERATIONS`), and the slots' scans give each of 8 lanes an eighth of
/// the slots, in two loops a scan ([`super::search::SEARCH_ONE_CPU_MAX`]). A scene beyond it is
/// refused on such an adapter rather than run without contact.
pub const CPU_ADAPTER_SLOTS: usize = 1 << 18;

/// How a scene's contact stage is solved and dispatched.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Path {
    /// The per-colour solve path (else one workgroup).
    pub multi: bool,
    /// On the one-workgroup path, the re-checks as their own dispatches.
    pub split: bool,
    /// On the one-workgroup path, extrapolated sweeps.
    pub extrapolate: bool,
    /// The stage in one workgroup before the search and one after it ([`one`]).
    pub one: bool,
    /// The search in one workgroup ([`search::search_one_path`]), at the start.
    pub search_one: bool,
    /// Whether and how the search switches between its two ways as the run goes
    /// ([`SearchSwitch`]).
    pub search_switch: Option<SearchSwitch>,
}

impl Path {
    /// The path `options` ask for, the rest by [`solve::multi_path`], [`solve::split_path`] and
    /// [`one::one_path`] for `nodes` contact nodes and `slots` slots.
    ///
    /// # Errors
    /// [`Error::Gpu`] when `options` ask for one workgroup with the per-colour path or split
    /// re-checks.
    pub fn choose(
        options: &ContactOptions,
        nodes: usize,
        slots: usize,
        device_type: wgpu::DeviceType,
    ) -> Result<Path> {
        if device_type == wgpu::DeviceType::Cpu && nodes.max(slots) > CPU_ADAPTER_SLOTS {
            return Err(Error::Gpu(format!(
                "the contact has {slots} slots and {nodes} nodes (an eroding body counts every \
                 node): on a CPU adapter (lavapipe) the contact search loses its candidates \
                 beyond {CPU_ADAPTER_SLOTS}, and the bodies would pass through each other; run \
                 this scene with --backend cpu"
            )));
        }
        let multi = options
            .multi
            .unwrap_or_else(|| solve::multi_path(slots, device_type));
        let split = options
            .split
            .unwrap_or_else(|| solve::split_path(slots, device_type));
        let one = options
            .one
            .unwrap_or_else(|| !multi && !split && one::one_path(nodes, device_type));
        if one && (multi || split) {
            return Err(Error::Gpu(
                "the contact stage in one workgroup takes neither the per-colour solve nor split \
                 re-checks"
                    .into(),
            ));
        }
        let search_one = options
            .search_one
            .unwrap_or_else(|| !multi && search::search_one_path(nodes, slots, device_type));
        if search_one && multi {
            return Err(Error::Gpu(
                "the search in one workgroup does not colour the slots for the per-colour solve"
                    .into(),
            ));
        }
        let most = search::SEARCH_ONE_CPU_MAX;
        if search_one && device_type == wgpu::DeviceType::Cpu && nodes.max(slots) > most {
            return Err(Error::Gpu(format!(
                "the search in one workgroup on a CPU adapter takes at most {most} contact nodes \
                 and slots (llvmpipe ends a shader's loops after 65 535 iterations in all); this \
                 contact has {nodes} nodes and {slots} slots"
            )));
        }
        let search_switch = match (options.search_one, options.search_switch) {
            (Some(_), Some(_)) => {
                return Err(Error::Gpu(
                    "the search's switch is not for a search whose way is set".into(),
                ))
            }
            (Some(_), None) => None,
            (None, Some(s)) => Some(s),
            (None, None) => search::search_switch(nodes, slots, device_type).filter(|_| !multi),
        };
        if let Some(s) = search_switch {
            if multi || s.window == 0 {
                return Err(Error::Gpu(format!(
                    "the search's switch (window {}) needs a window of at least one step and the \
                     one-workgroup solve",
                    s.window
                )));
            }
            if device_type == wgpu::DeviceType::Cpu && nodes.max(slots) > most {
                return Err(Error::Gpu(format!(
                    "the search's switch on a CPU adapter takes at most {most} contact nodes and \
                     slots (llvmpipe ends a shader's loops after 65 535 iterations in all); this \
                     contact has {nodes} nodes and {slots} slots"
                )));
            }
        }
        Ok(Path {
            multi,
            split,
            extrapolate: !options.plain_sweeps,
            one,
            search_one,
            search_switch,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A contact beyond [`CPU_ADAPTER_SLOTS`] slots or nodes is refused on a CPU adapter (with a
    /// message naming the CPU backend) and taken on a GPU.
    #[test]
    fn a_contact_beyond_the_cpu_adapters_limit_is_refused_there_only() {
        let o = ContactOptions::default();
        let (at, over) = (CPU_ADAPTER_SLOTS, CPU_ADAPTER_SLOTS + 1);
        assert!(Path::choose(&o, at, at, wgpu::DeviceType::Cpu).is_ok());
        for (nodes, slots) in [(over, 10), (10, over)] {
            match Path::choose(&o, nodes, slots, wgpu::DeviceType::Cpu) {
                Err(Error::Gpu(m)) => assert!(m.contains("--backend cpu"), "{m}"),
                other => panic!("{other:?}"),
            }
            assert!(Path::choose(&o, nodes, slots, wgpu::DeviceType::DiscreteGpu).is_ok());
        }
    }

    /// The search's switch: by default on a GPU beyond [`search::SEARCH_ONE_ITEMS`] and up to
    /// [`search::SEARCH_ONE_RARE_ITEMS`] (starting per item), never on a CPU adapter nor with the
    /// search's way set; asked for, on a CPU adapter only up to [`search::SEARCH_ONE_CPU_MAX`].
    #[test]
    fn the_search_switches_where_it_may() {
        let o = ContactOptions {
            multi: Some(false),
            ..ContactOptions::default()
        };
        let gpu = wgpu::DeviceType::DiscreteGpu;
        let cpu = wgpu::DeviceType::Cpu;
        let path = |o: &ContactOptions, n: usize, d| {
            Path::choose(o, n, n, d).map(|p| (p.search_one, p.search_switch))
        };
        let (below, low, high, over) = (
            search::SEARCH_ONE_ITEMS,
            search::SEARCH_ONE_ITEMS + 1,
            search::SEARCH_ONE_RARE_ITEMS,
            search::SEARCH_ONE_RARE_ITEMS + 1,
        );
        let default = Some(search::SEARCH_SWITCH);
        assert_eq!(path(&o, below, gpu).ok(), Some((true, None)));
        assert_eq!(path(&o, low, gpu).ok(), Some((false, default)));
        assert_eq!(path(&o, high, gpu).ok(), Some((false, default)));
        assert_eq!(path(&o, over, gpu).ok(), Some((false, None)));
        assert_eq!(path(&o, low, cpu).ok(), Some((false, None)));
        let set = ContactOptions {
            search_one: Some(false),
            ..o
        };
        assert_eq!(path(&set, low, gpu).ok(), Some((false, None)));
        let asked = ContactOptions {
            search_switch: Some(SearchSwitch {
                window: 4,
                searches: 1,
            }),
            ..o
        };
        assert_eq!(
            path(&asked, search::SEARCH_ONE_CPU_MAX, cpu).ok(),
            Some((false, asked.search_switch))
        );
        assert!(path(&asked, search::SEARCH_ONE_CPU_MAX + 1, cpu).is_err());
        let zero = ContactOptions {
            search_switch: Some(SearchSwitch {
                window: 0,
                searches: 1,
            }),
            ..o
        };
        assert!(path(&zero, 10, gpu).is_err());
    }

    /// The search in one workgroup: by default on a GPU up to [`search::SEARCH_ONE_ITEMS`] and
    /// never on a CPU adapter, where asking for it beyond [`search::SEARCH_ONE_CPU_MAX`] is
    /// refused (llvmpipe's loop budget), and never with the per-colour solve.
    #[test]
    fn the_search_in_one_workgroup_is_taken_where_it_fits() {
        let o = ContactOptions {
            multi: Some(false),
            ..ContactOptions::default()
        };
        let gpu = wgpu::DeviceType::DiscreteGpu;
        let cpu = wgpu::DeviceType::Cpu;
        let (at, over) = (search::SEARCH_ONE_ITEMS, search::SEARCH_ONE_ITEMS + 1);
        let path = |o: &ContactOptions, n: usize, d| Path::choose(o, n, n, d).map(|p| p.search_one);
        assert_eq!(path(&o, at, gpu).ok(), Some(true));
        assert_eq!(path(&o, over, gpu).ok(), Some(false));
        assert_eq!(path(&o, 10, cpu).ok(), Some(false));
        let forced = ContactOptions {
            search_one: Some(true),
            ..o
        };
        assert_eq!(
            path(&forced, search::SEARCH_ONE_CPU_MAX, cpu).ok(),
            Some(true)
        );
        match path(&forced, search::SEARCH_ONE_CPU_MAX + 1, cpu) {
            Err(Error::Gpu(m)) => assert!(m.contains("65 535"), "{m}"),
            other => panic!("{other:?}"),
        }
        let multi = ContactOptions {
            multi: Some(true),
            search_one: Some(true),
            ..ContactOptions::default()
        };
        assert!(path(&multi, 10, gpu).is_err());
    }
}
