//! The expander on small documents of its own: each construct, and bad input whose message
//! must name the file and line.

use std::path::Path;

use urdf_xacro::{expand_file, Options, XacroError};

const NS: &str = r#"xmlns:xacro="http://www.ros.org/wiki/xacro""#;

/// Writes `files` (path, text) into a temporary folder and expands the first.
fn expand_in(
    files: &[(&str, &str)],
    opts: &Options,
) -> (tempfile::TempDir, Result<String, XacroError>) {
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in files {
        let p = dir.path().join(name);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, text).unwrap();
    }
    let top = dir.path().join(files[0].0);
    let r = expand_file(&top, opts).map(|e| e.xml);
    (dir, r)
}

/// Expands one document, the body of a `<robot>` with the xacro namespace.
fn body(inner: &str) -> Result<String, XacroError> {
    let doc = format!("<robot name=\"r\" {NS}>\n{inner}\n</robot>");
    expand_in(&[("top.xacro", &doc)], &Options::default()).1
}

/// The expanded robot's content without whitespace between elements.
fn ok(inner: &str) -> String {
    let xml = body(inner).unwrap_or_else(|e| panic!("{e}"));
    let start = xml.find("<robot").unwrap();
    let compact: String = xml[start..]
        .split('\n')
        .map(str::trim)
        .collect::<Vec<_>>()
        .join("");
    compact
        .trim_start_matches("<robot name=\"r\">")
        .trim_end_matches("</robot>")
        .to_string()
}

fn err(inner: &str) -> String {
    match body(inner) {
        Ok(xml) => panic!("expected an error, found {xml}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn properties_are_lazy_and_scoped() {
    // Used before the property it refers to is defined: lazy.
    assert_eq!(
        ok(
            r#"<xacro:property name="b" value="${a * 2}"/><xacro:property name="a" value="0.5"/><x v="${b}"/>"#
        ),
        r#"<x v="1.0"/>"#
    );
    // A macro's properties stay in the macro, unless scope="parent" or "global".
    assert_eq!(
        ok(r#"<xacro:property name="p" value="outer"/>
              <xacro:macro name="m"><xacro:property name="p" value="inner"/><in v="${p}"/>
                <xacro:property name="up" value="${p}!" scope="parent"/>
                <xacro:property name="g" value="G" scope="global"/></xacro:macro>
              <xacro:m/><out v="${p} ${up} ${g}"/>"#),
        r#"<in v="inner"/><out v="outer inner! G"/>"#
    );
    // default= sets only what is not set.
    assert_eq!(
        ok(
            r#"<xacro:property name="a" value="1"/><xacro:property name="a" default="2"/>
              <xacro:property name="b" default="3"/><x v="${a}${b}"/>"#
        ),
        r#"<x v="13"/>"#
    );
    // A block property is inserted as its content.
    assert_eq!(
        ok(
            r#"<xacro:property name="blk"><a/><b/></xacro:property><xacro:insert_block name="blk"/>"#
        ),
        "<a/><b/>"
    );
    // Literal conversion: numbers stay numbers, quoted strings lose their quotes.
    assert_eq!(
        ok(
            r#"<xacro:property name="n" value="2"/><xacro:property name="s" value="'x y'"/><x v="${n*2} ${s}"/>"#
        ),
        r#"<x v="4 x y"/>"#
    );
}

#[test]
fn macros_take_defaults_forwarding_and_blocks() {
    let defs = r#"<xacro:property name="side" value="left"/>
        <xacro:macro name="j" params="name x:=0.1 side:=^ pre:=^|p_ *origin **extra">
          <joint name="${pre}${name}_${side}" x="${x}"><xacro:insert_block name="origin"/>
            <xacro:insert_block name="extra"/></joint>
        </xacro:macro>"#;
    let call = r#"<xacro:j name="a"><origin xyz="1 2 3"/><e><f/><g/></e></xacro:j>"#;
    assert_eq!(
        ok(&format!("{defs}{call}")),
        r#"<joint name="p_a_left" x="0.1"><origin xyz="1 2 3"/><f/><g/></joint>"#
    );
    let call = r#"<xacro:j name="b" x="${2*0.5}" side="right" pre=""><o/><e/></xacro:j>"#;
    assert_eq!(
        ok(&format!("{defs}{call}")),
        r#"<joint name="b_right" x="1.0"><o/></joint>"#
    );
    // A forwarded parameter without a default and without an outer property is an error.
    let e = err(r#"<xacro:macro name="m" params="k:=^"><x/></xacro:macro><xacro:m/>"#);
    assert!(e.contains("undefined property to forward: 'k'"), "{e}");
    // Nested macros and a macro defined inside a macro (local to it).
    assert_eq!(
        ok(
            r#"<xacro:macro name="outer" params="n"><xacro:macro name="inner" params="m"><i v="${m}"/></xacro:macro>
              <xacro:inner m="${n}1"/><xacro:inner m="${n}2"/></xacro:macro><xacro:outer n="x"/>"#
        ),
        r#"<i v="x1"/><i v="x2"/>"#
    );
    let e = err(
        r#"<xacro:macro name="outer"><xacro:macro name="inner"><i/></xacro:macro></xacro:macro><xacro:outer/><xacro:inner/>"#,
    );
    assert!(e.contains("unknown macro name: xacro:inner"), "{e}");
    // xacro:call by a computed name.
    assert_eq!(
        ok(
            r#"<xacro:macro name="m1"><one/></xacro:macro><xacro:property name="k" value="1"/><xacro:call macro="m${k}"/>"#
        ),
        "<one/>"
    );
}

#[test]
fn conditionals_elements_and_attributes() {
    assert_eq!(
        ok(r#"<xacro:property name="g" value="true"/>
              <xacro:if value="${g}"><a/></xacro:if><xacro:unless value="${g}"><b/></xacro:unless>
              <xacro:if value="0"><c/></xacro:if><xacro:if value="${1 == 1 and not False}"><d/></xacro:if>"#),
        "<a/><d/>"
    );
    assert_eq!(
        ok(r#"<xacro:property name="t" value="link"/>
              <xacro:element xacro:name="${t}" name="l1"><xacro:attribute name="extra" value="${1+1}"/></xacro:element>"#),
        r#"<link name="l1" extra="2"/>"#
    );
    let e = err(r#"<xacro:if value="maybe"><a/></xacro:if>"#);
    assert!(
        e.contains("line 2") && e.contains("expected a boolean"),
        "{e}"
    );
}

#[test]
fn args_eval_env_and_dirname() {
    let doc = format!(
        r#"<robot name="r" {NS}><xacro:arg name="arm" default="gen3"/><xacro:arg name="dof" default="6"/>
           <a v="$(arg arm)" n="$(eval dof + 1)" e="$(eval arm == 'gen3')" o="$(optenv URDF_XACRO_UNSET_VAR 1 2)"
              d="$(dirname)" c="$${{x}}"/></robot>"#
    );
    let mut opts = Options::default();
    opts.add_arg("dof:=7").unwrap();
    let (dir, xml) = expand_in(&[("top.xacro", &doc)], &opts);
    let xml = xml.unwrap();
    let here = std::path::absolute(dir.path()).unwrap();
    assert!(xml.contains(r#"v="gen3""#), "{xml}");
    assert!(xml.contains(r#"n="8""#), "{xml}");
    assert!(xml.contains(r#"e="True""#), "{xml}");
    assert!(xml.contains(r#"o="1 2""#), "{xml}");
    assert!(xml.contains(&format!(r#"d="{}""#, here.display())), "{xml}");
    assert!(xml.contains(r#"c="${x}""#), "{xml}");
    let e = err(r#"<a v="$(arg nope)"/>"#);
    assert!(e.contains("undefined argument 'nope'"), "{e}");
    let e = err(r#"<a v="$(env URDF_XACRO_UNSET_VAR)"/>"#);
    assert!(e.contains("URDF_XACRO_UNSET_VAR is not set"), "{e}");
}

#[test]
fn includes_find_packages_and_load_yaml() {
    let top = format!(
        r#"<robot name="r" {NS}><xacro:include filename="$(find arm_pkg)/urdf/parts.xacro"/>
           <xacro:property name="cfg" value="${{xacro.load_yaml('$(find arm_pkg)/config/j.yaml')}}"/>
           <xacro:part n="${{cfg['joints'][1]}}" a="${{cfg.limits.upper}}"/></robot>"#
    );
    let parts = format!(
        r#"<robot {NS}><xacro:include filename="more.xacro"/>
           <xacro:macro name="part" params="n a"><p n="${{n}}" a="${{a}}" k="${{k}}"/></xacro:macro></robot>"#
    );
    let more = format!(r#"<robot {NS}><xacro:property name="k" value="${{pi/2}}"/></robot>"#);
    let yaml = "joints: [j1, j2]\nlimits:\n  upper: !degrees 90\n";
    let files = [
        ("top.xacro", top.as_str()),
        ("arm/package.xml", "<package><name>arm_pkg</name></package>"),
        ("arm/urdf/parts.xacro", parts.as_str()),
        ("arm/urdf/more.xacro", more.as_str()),
        ("arm/config/j.yaml", yaml),
    ];
    // Through --package ...
    let dir = tempfile::tempdir().unwrap();
    let mut opts = Options::default();
    opts.add_package(&format!("arm_pkg={}", dir.path().join("arm").display()))
        .unwrap();
    for (name, text) in &files {
        let p = dir.path().join(name);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, text).unwrap();
    }
    let xml = expand_file(&dir.path().join("top.xacro"), &opts)
        .unwrap()
        .xml;
    assert!(
        xml.contains(r#"<p n="j2" a="1.5707963267948966" k="1.5707963267948966"/>"#),
        "{xml}"
    );
    // ... and a package that is found nowhere.
    let (_d, r) = expand_in(&files[..1], &Options::default());
    let e = r.unwrap_err().to_string();
    assert!(
        e.starts_with("top.xacro: line 1: package 'arm_pkg' not found"),
        "{e}"
    );
}

#[test]
fn ros_package_path_is_walked() {
    let dir = tempfile::tempdir().unwrap();
    let pkg = dir.path().join("ws/src/deep/my_robot");
    std::fs::create_dir_all(&pkg).unwrap();
    std::fs::write(
        pkg.join("package.xml"),
        "<package>\n <name>my_robot</name>\n</package>",
    )
    .unwrap();
    std::fs::write(
        pkg.join("arm.xacro"),
        format!(r#"<robot {NS}><arm/></robot>"#),
    )
    .unwrap();
    let top = dir.path().join("top.xacro");
    std::fs::write(
        &top,
        format!(
            r#"<robot name="r" {NS}><xacro:include filename="$(find my_robot)/arm.xacro"/></robot>"#
        ),
    )
    .unwrap();
    // Only this test reads ROS_PACKAGE_PATH (the others give --package or expect a failure
    // that does not depend on it).
    std::env::set_var("ROS_PACKAGE_PATH", dir.path().join("ws"));
    let r = expand_file(&top, &Options::default());
    std::env::remove_var("ROS_PACKAGE_PATH");
    assert!(r.unwrap().xml.contains("<arm/>"));
}

#[test]
fn errors_name_file_line_and_include_chain() {
    let e = err("\n<a v=\"${nope * 2}\"/>");
    assert_eq!(
        e,
        "top.xacro: line 3: undefined name 'nope' in '${nope * 2}'"
    );
    let e = err(r#"<a v="${1/0}"/>"#);
    assert!(e.starts_with("top.xacro: line 2: division by zero"), "{e}");
    let e = err(r#"<xacro:macro name="m"><a v="${q}"/></xacro:macro>
        <xacro:m/>"#);
    assert!(
        e.contains("in macro 'm' called at top.xacro: line 3"),
        "{e}"
    );
    let e = err(
        r#"<xacro:property name="a" value="${b}"/><xacro:property name="b" value="${a}"/><x v="${a}"/>"#,
    );
    assert!(
        e.contains("circular property definition: a -> b -> a"),
        "{e}"
    );
    let e = err(r#"<xacro:nosuch/>"#);
    assert!(e.contains("unknown macro name: xacro:nosuch"), "{e}");
    let e = err(r#"<xacro:macro name="m" params="a"/><xacro:m b="1"/>"#);
    assert!(e.contains("macro 'm' has no parameter 'b'"), "{e}");
    let e = err(r#"<xacro:macro name="m" params="a"/><xacro:m/>"#);
    assert!(e.contains("parameters not set: a"), "{e}");

    let top = format!("<robot name=\"r\" {NS}>\n<xacro:include filename=\"a.xacro\"/></robot>");
    let a = format!("<robot {NS}>\n\n<b v=\"${{oops}}\"/></robot>");
    let (_d, r) = expand_in(&[("top.xacro", &top), ("a.xacro", &a)], &Options::default());
    assert_eq!(
        r.unwrap_err().to_string(),
        "a.xacro: line 3: undefined name 'oops' in '${oops}' (included from top.xacro: line 2)"
    );
    let (_d, r) = expand_in(
        &[("top.xacro", "<robot><unclosed></robot>")],
        &Options::default(),
    );
    let e = r.unwrap_err().to_string();
    assert!(e.starts_with("top.xacro: invalid XML"), "{e}");
    // What Python's namespace-unaware parser reads and this one does not is "unsupported".
    for (text, construct) in [
        (
            "<robot><sensor:camera/></robot>",
            "undeclared namespace prefixes",
        ),
        ("<!DOCTYPE robot><robot/>", "document type declarations"),
    ] {
        let (_d, r) = expand_in(&[("top.xacro", text)], &Options::default());
        match r {
            Err(XacroError::Unsupported { construct: c, .. }) => assert_eq!(c, construct),
            other => panic!("{text}: {other:?}"),
        }
    }
}

#[test]
fn recursion_cycles_and_size_are_guarded() {
    let e = err(r#"<xacro:macro name="m"><xacro:m/></xacro:macro><xacro:m/>"#);
    assert!(e.contains("macro calls nested deeper than 100"), "{e}");
    let a = format!(r#"<robot {NS}><xacro:include filename="b.xacro"/></robot>"#);
    let b = format!(r#"<robot {NS}><xacro:include filename="a.xacro"/></robot>"#);
    let (_d, r) = expand_in(&[("a.xacro", &a), ("b.xacro", &b)], &Options::default());
    let e = r.unwrap_err().to_string();
    assert!(
        e.contains("include cycle: a.xacro -> b.xacro -> a.xacro"),
        "{e}"
    );
    // Ten calls of ten calls ... eight deep: 10^8 elements, refused at the size limit.
    let mut doc = String::from(
        r#"<xacro:macro name="m0"><leaf name="a fairly long attribute value to fill the output"/></xacro:macro>"#,
    );
    for k in 1..=8 {
        doc.push_str(&format!(
            r#"<xacro:macro name="m{k}">{}</xacro:macro>"#,
            format!("<xacro:m{}/>", k - 1).repeat(10)
        ));
    }
    doc.push_str("<xacro:m8/>");
    let doc = format!("<robot name=\"r\" {NS}>{doc}</robot>");
    // The default limit (64 MiB) is guarded the same way; a smaller one keeps the test fast.
    let opts = Options {
        max_bytes: Some(1 << 20),
        ..Options::default()
    };
    let (_d, r) = expand_in(&[("top.xacro", &doc)], &opts);
    let e = r.unwrap_err().to_string();
    assert!(
        e.contains("the expanded document exceeds 1048576 bytes"),
        "{e}"
    );
    // Calls that write nothing are counted too.
    let empty = doc.replace(
        r#"<leaf name="a fairly long attribute value to fill the output"/>"#,
        "",
    );
    let (_d, r) = expand_in(&[("top.xacro", &empty)], &opts);
    let e = r.unwrap_err().to_string();
    assert!(
        e.contains("the expanded document exceeds 1048576 bytes"),
        "{e}"
    );
}

#[test]
fn unsupported_constructs_are_refused_by_name() {
    for (inner, construct) in [
        (r#"<a v="${(lambda x: x)(1)}"/>"#, "lambda expressions"),
        (
            r#"<xacro:include filename="*.xacro"/>"#,
            "includes with a glob pattern",
        ),
        (
            r#"<xacro:include filename="a.xacro" ns="n"/>"#,
            "namespaced includes (ns=)",
        ),
    ] {
        match body(inner) {
            Err(XacroError::Unsupported {
                construct: c,
                message,
            }) => {
                assert_eq!(c, construct);
                assert!(message.starts_with("top.xacro: line 2:"), "{message}");
            }
            other => panic!("{inner}: expected unsupported, found {other:?}"),
        }
    }
}

#[test]
fn output_is_well_formed_xml() {
    let xml = body(r#"<a v="${'&lt;&quot;'}">x &amp; y<!-- kept --></a>"#).unwrap();
    let doc = roxmltree::Document::parse(&xml).unwrap();
    let a = doc.descendants().find(|n| n.has_tag_name("a")).unwrap();
    assert_eq!(a.attribute("v"), Some("<\""));
    assert_eq!(a.text(), Some("x & y"));
    assert!(!xml.contains("xmlns:xacro"));
    assert!(Path::new("unused").is_relative());
}
