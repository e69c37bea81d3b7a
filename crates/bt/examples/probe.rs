use bt::{ReadOptions, TreeParams};
use petri::{CompiledGspn, ExploreParams, Params, ReachabilityGraph};
fn main() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/bt/nav2");
    let params = TreeParams::read_file(format!("{dir}/nominal.toml")).unwrap();
    for f in std::env::args().skip(1) {
    let tree = bt::read_file(format!("{dir}/{f}"), &ReadOptions::default()).unwrap();
    let t0 = std::time::Instant::now();
    let tr = bt::translate::translate(&tree, &params).unwrap();
    let g = tr.net.instantiate(&Params::new()).unwrap();
    let t_tr = t0.elapsed();
    let t0 = std::time::Instant::now();
    let rg = ReachabilityGraph::explore(&g, &ExploreParams::default()).unwrap();
    let t_rg = t0.elapsed();
    let st = rg.stats().clone();
    let t0 = std::time::Instant::now();
    let c = CompiledGspn::from_graph(g.clone(), rg).unwrap();
    let t_c = t0.elapsed();
    let rates = g.rates(&Params::new(), None).unwrap();
    let t0 = std::time::Instant::now();
    let a = c.absorption(&rates).unwrap();
    let t_a = t0.elapsed();
    let t0 = std::time::Instant::now();
    let _ = c.absorption_cdf_grid(&rates, a.mean_time * 20.0, 300).unwrap();
    let t_q = t0.elapsed();
    struct G(Vec<Vec<u32>>);
    impl petri::scc::Successors for G { fn num_nodes(&self)->usize{self.0.len()} fn successors(&self,v:u32)->&[u32]{&self.0[v as usize]} }
    let gg = G((0..c.num_tangible()).map(|s| c.entries_from(s).filter(|e| e.0 as usize != s).map(|e| e.0).collect()).collect());
    let mut sizes = std::collections::BTreeMap::<usize,usize>::new();
    petri::scc::tarjan(&gg, |_| true, |comp: &[u32]| -> Result<(),()> { *sizes.entry(comp.len()).or_default() += 1; Ok(()) }).unwrap();
    println!("scc sizes {:?}", sizes);
    let t0 = std::time::Instant::now();
    let o = bt::AnalyzeOptions { sensitivities: false, ..Default::default() };
    let r = bt::analyze(&tree, &params, &o).unwrap();
    let t_all = t0.elapsed();
    println!("{f}: P/T {:.5} {:.4} | {} places {} trans | markings {} tangible {} edges {} | translate {:?} rg {:?} compile {:?} absorb {:?} cdf {:?} | analyze {:?}",
      r.p_success, r.mean_time, g.num_places(), g.num_transitions(), st.markings, st.tangible, st.edges, t_tr, t_rg, t_c, t_a, t_q, t_all);
    }
}
