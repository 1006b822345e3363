//! Speed of reading URDFs at scale: documents of ignored elements (`<gazebo/>`), long serial
//! chains, and many leaves (refused as ambiguous without a tip), each at two sizes to show
//! linear growth. Inputs are generated in memory.

use std::fmt::Write;
use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use urdf_axes::UrdfModel;

const ARM: &str = r#"<robot name="arm">
  <link name="base_link"/><link name="link_1"/><link name="tool0"/>
  <joint name="j1" type="revolute"><parent link="base_link"/><child link="link_1"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="link_1"/><child link="tool0"/><origin xyz="0.3 0 0"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
"#;

/// The two-joint arm followed by `n` empty `<gazebo/>` elements.
fn gazebo(n: usize) -> String {
    let mut s = String::from(ARM);
    for i in 0..n {
        s.push_str("<gazebo/>");
        if i % 10 == 9 {
            s.push('\n');
        }
    }
    s.push_str("</robot>\n");
    s
}

/// A serial chain of `n` revolute joints.
fn chain(n: usize) -> String {
    let mut s = String::from("<robot name=\"long\">\n<link name=\"l0\"/>\n");
    for i in 1..=n {
        let _ = writeln!(s, "<link name=\"l{i}\"/>");
    }
    for i in 1..=n {
        let _ = writeln!(
            s,
            "<joint name=\"j{i}\" type=\"revolute\"><parent link=\"l{}\"/><child link=\"l{i}\"/>\
             <origin xyz=\"0 0 0.001\" rpy=\"0 0 0\"/><axis xyz=\"0 0 1\"/>\
             <limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>",
            i - 1
        );
    }
    s.push_str("</robot>\n");
    s
}

/// `n` one-joint branches off one base link: `n` equally long arms.
fn leaves(n: usize) -> String {
    let mut s = String::from("<robot name=\"leaves\">\n<link name=\"base\"/>\n");
    for i in 0..n {
        let _ = writeln!(s, "<link name=\"leaf_{i}\"/>");
    }
    for i in 0..n {
        let _ = writeln!(
            s,
            "<joint name=\"j{i}\" type=\"continuous\"><parent link=\"base\"/><child link=\"leaf_{i}\"/>\
             <origin xyz=\"0 0 0.1\"/><axis xyz=\"0 0 1\"/></joint>"
        );
    }
    s.push_str("</robot>\n");
    s
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("parse_and_chain");
    g.sample_size(10);
    for (name, text) in [
        ("gazebo_100k", gazebo(100_000)),
        ("gazebo_1m", gazebo(1_000_000)),
        ("chain_1k", chain(1_000)),
        ("chain_10k", chain(10_000)),
        ("leaves_2k", leaves(2_000)),
        ("leaves_20k", leaves(20_000)),
    ] {
        g.throughput(Throughput::Bytes(text.len() as u64));
        g.bench_with_input(BenchmarkId::from_parameter(name), &text, |b, t| {
            b.iter(|| {
                let model = UrdfModel::parse(black_box(t)).expect("valid urdf");
                // The leaves are refused as ambiguous; the others give a chain.
                black_box(model.chain(None, None).ok())
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
