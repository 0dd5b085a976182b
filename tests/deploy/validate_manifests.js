'use strict';
// Validates every Kubernetes manifest under a folder against the API schemas of a fixed
// Kubernetes version: the OpenAPI schemas that the npm package kubernetes-models compiles into
// one validate function per kind (KUBERNETES_VERSION below; the package is pinned by
// package-lock.json). Called by run_validate.sh.
//
//   node validate_manifests.js [--no-self-test] DIR
//
// Every *.yaml / *.yml file under DIR, every document in it (multi-document YAML), must
//   - parse as YAML without errors or warnings (duplicate keys included),
//   - name an apiVersion and kind that Kubernetes KUBERNETES_VERSION serves,
//   - pass that kind's schema (types, required fields, enums, formats), and
//   - hold no field the schema does not define (what `kubectl apply --validate=strict` and the
//     API server's strict field validation refuse; the schemas alone would let a misspelt
//     `livenesProbe` through and Kubernetes would drop it).
// Before that, a self-test checks that the validator refuses broken documents made here from a
// real one (containers: "x", unknown fields, a missing required field, a wrong apiVersion, a
// duplicate YAML key): a validator that accepts everything would pass nothing.
//
// Exit status 0 when the self-test and every document passed; 1 otherwise, naming each error as
// FILE#DOCUMENT (kind/name): /json/pointer message.
const fs = require('node:fs');
const path = require('node:path');
const YAML = require('yaml');

// kubernetes-models 4.5.x carries the schemas of Kubernetes v1.33.0 (its changelog: "Update
// schema version to v1.33.0"); 5.x (v1.36.0) needs Node 22, 4.5.1 runs on Node 14 and later.
const KUBERNETES_VERSION = 'v1.33.0';
const MODELS_VERSION = require('kubernetes-models/package.json').version;

// apiVersion -> the kubernetes-models module of that group and version ("apps/v1" ->
// kubernetes-models/apps/v1, "v1" -> kubernetes-models/v1).
function modelFor(apiVersion, kind) {
  if (typeof apiVersion !== 'string' || !/^([a-z0-9.-]+\/)?v[0-9]+((alpha|beta)[0-9]+)?$/.test(apiVersion)) {
    return { error: `apiVersion ${JSON.stringify(apiVersion)} is not a Kubernetes API version` };
  }
  if (typeof kind !== 'string' || !/^[A-Z][A-Za-z0-9]*$/.test(kind)) {
    return { error: `kind ${JSON.stringify(kind)} is not a Kubernetes kind` };
  }
  let group;
  try {
    group = require(`kubernetes-models/${apiVersion}`);
  } catch (e) {
    if (e.code !== 'MODULE_NOT_FOUND' && e.code !== 'ERR_PACKAGE_PATH_NOT_EXPORTED') throw e;
    return { error: `apiVersion ${apiVersion} is not served by Kubernetes ${KUBERNETES_VERSION}` };
  }
  const model = group[kind];
  if (typeof model !== 'function' || model.apiVersion !== apiVersion || model.kind !== kind) {
    return { error: `kind ${kind} is not in ${apiVersion} (Kubernetes ${KUBERNETES_VERSION})` };
  }
  return { model };
}

// Unknown fields. The compiled schema validators do not refuse properties they do not define,
// but for an object schema with `properties` they read every property they define (to check it
// or to see that it is absent), and for a map (`additionalProperties`) they read every key. So
// the document is handed to the validator behind a Proxy that records which keys were read on
// each object: a key of an object that the validator looked into but never read is not in the
// schema. An object the validator never looked into (a free-form field such as a RawExtension)
// is not judged. The self-test below shows that this finds unknown fields and the real
// manifests show that it accepts the fields the schemas define.
function validateStrict(model, doc) {
  const reads = new WeakMap(); // object -> Set of keys the validator read
  const proxies = new WeakMap();
  const wrap = (value) => {
    if (value === null || typeof value !== 'object') return value;
    let proxy = proxies.get(value);
    if (!proxy) {
      const keys = new Set();
      reads.set(value, keys);
      proxy = new Proxy(value, {
        get(target, key) {
          if (typeof key === 'string') keys.add(key);
          return wrap(Reflect.get(target, key));
        },
      });
      proxies.set(value, proxy);
    }
    return proxy;
  };

  const errors = [];
  try {
    // The model's own validate(): the package's error messages ("data/spec/... must be array").
    model.prototype.validate.call(wrap(doc));
  } catch (e) {
    if (!Array.isArray(e.errors)) throw e;
    for (const err of e.errors) {
      let message = err.message;
      if (err.keyword === 'enum') message += `: ${err.params.allowedValues.join(', ')}`;
      errors.push(`${err.instancePath || '/'} ${message}`);
    }
  }

  const walk = (value, pointer) => {
    if (value === null || typeof value !== 'object') return;
    if (Array.isArray(value)) {
      value.forEach((item, i) => walk(item, `${pointer}/${i}`));
      return;
    }
    const keys = reads.get(value);
    const judged = keys !== undefined && keys.size > 0;
    for (const key of Object.keys(value)) {
      const child = `${pointer}/${key.replace(/~/g, '~0').replace(/\//g, '~1')}`;
      if (judged && !keys.has(key)) {
        errors.push(`${child} is not a field of this object in Kubernetes ${KUBERNETES_VERSION}`);
      } else {
        walk(value[key], child);
      }
    }
  };
  walk(doc, '');
  return errors;
}

// One document (already parsed) -> list of error strings.
function validateDocument(doc) {
  if (doc === null || typeof doc !== 'object' || Array.isArray(doc)) {
    return ['/ the document is not a mapping (a Kubernetes object)'];
  }
  const found = modelFor(doc.apiVersion, doc.kind);
  if (found.error) return [`/ ${found.error}`];
  return validateStrict(found.model, doc);
}

// YAML text -> [{index, doc, errors}]; YAML errors and warnings are errors.
function parseDocuments(text) {
  const out = [];
  YAML.parseAllDocuments(text, { prettyErrors: true, uniqueKeys: true }).forEach((document, index) => {
    const problems = [...document.errors, ...document.warnings].map((e) => `YAML: ${e.message.split('\n')[0]}`);
    // A trailing "---" or a file's comments alone give an empty document: nothing to apply.
    if (problems.length === 0 && document.contents === null) return;
    out.push({ index, doc: problems.length ? null : document.toJS(), errors: problems });
  });
  return out;
}

function validateText(text) {
  return parseDocuments(text).map((d) => ({ ...d, errors: d.errors.length ? d.errors : validateDocument(d.doc) }));
}

function findManifests(dir) {
  const files = [];
  for (const entry of fs.readdirSync(dir, { withFileTypes: true })) {
    const full = path.join(dir, entry.name);
    if (entry.isDirectory()) files.push(...findManifests(full));
    else if (/\.ya?ml$/.test(entry.name)) files.push(full);
  }
  return files.sort();
}

// ---------------------------------------------------------------------------------------------
// Self-test: broken documents made from a real Deployment must each fail with the expected error.

function selfTest(deployment) {
  const clone = () => JSON.parse(JSON.stringify(deployment));
  const podSpec = (d) => d.spec.template.spec;
  const cases = [
    ['containers is a string', (d) => { podSpec(d).containers = 'x'; }, '/spec/template/spec/containers must be array'],
    ['unknown field in spec', (d) => { d.spec.replica = 2; }, '/spec/replica is not a field'],
    ['misspelt probe in a container', (d) => {
      const c = podSpec(d).containers[0];
      c.livenesProbe = c.livenessProbe;
      delete c.livenessProbe;
    }, '/spec/template/spec/containers/0/livenesProbe is not a field'],
    ['unknown top-level field', (d) => { d.specs = d.spec; }, '/specs is not a field'],
    ['selector missing', (d) => { delete d.spec.selector; }, '/spec must have required property selector'],
    ['replicas is a string', (d) => { d.spec.replicas = 'two'; }, '/spec/replicas must be integer'],
    ['bad enum', (d) => { podSpec(d).restartPolicy = 'Sometimes'; }, '/spec/template/spec/restartPolicy must be equal to one of the allowed values'],
    ['apiVersion not served', (d) => { d.apiVersion = 'apps/v1beta9'; }, 'apiVersion apps/v1beta9 is not served'],
    ['kind not in the group', (d) => { d.kind = 'Deploymnt'; }, 'kind Deploymnt is not in apps/v1'],
  ];
  const failures = [];
  const baseline = validateDocument(clone());
  if (baseline.length) failures.push(`the unchanged Deployment does not pass: ${baseline.join('; ')}`);
  for (const [name, mutate, expected] of cases) {
    const doc = clone();
    mutate(doc);
    const errors = validateDocument(doc);
    if (!errors.some((e) => e.includes(expected))) {
      failures.push(`${name}: expected an error containing "${expected}", got ${errors.length ? errors.join('; ') : 'none'}`);
    } else {
      console.log(`k8s-validate: self-test: ${name}: refused (${errors.find((e) => e.includes(expected))})`);
    }
  }
  // YAML the API server would refuse or read differently: a duplicate key.
  const duplicate = validateText(`${YAML.stringify(clone())}kind: Service\n`);
  if (!duplicate.some((d) => d.errors.some((e) => e.startsWith('YAML:')))) {
    failures.push('duplicate key: expected a YAML error, got none');
  } else {
    console.log('k8s-validate: self-test: duplicate YAML key: refused');
  }
  return failures;
}

function main() {
  const args = process.argv.slice(2);
  const runSelfTest = args[0] !== '--no-self-test';
  if (!runSelfTest) args.shift();
  const dir = args[0];
  if (!dir || args.length !== 1) {
    console.error('usage: node validate_manifests.js [--no-self-test] DIR');
    process.exit(2);
  }
  console.log(`k8s-validate: schemas of Kubernetes ${KUBERNETES_VERSION} (kubernetes-models ${MODELS_VERSION})`);
  const files = findManifests(dir);
  if (files.length === 0) {
    console.error(`k8s-validate: FAILED: no *.yaml under ${dir}`);
    process.exit(1);
  }

  let failed = 0;
  let documents = 0;
  let deployment = null;
  for (const file of files) {
    const relative = path.relative(process.cwd(), file);
    const name = relative.startsWith('..') ? file : relative;
    const results = validateText(fs.readFileSync(file, 'utf8'));
    if (results.length === 0) {
      console.error(`k8s-validate: FAILED: ${name}: no Kubernetes object in it`);
      failed++;
    }
    for (const { index, doc, errors } of results) {
      documents++;
      const what = doc ? `${doc.kind}/${doc.metadata && doc.metadata.name}` : '?';
      if (errors.length) {
        failed++;
        for (const e of errors) console.error(`k8s-validate: FAILED: ${name}#${index} (${what}): ${e}`);
      } else {
        console.log(`k8s-validate: ${name}#${index} ${doc.apiVersion} ${what}: valid`);
        if (!deployment && doc.kind === 'Deployment') deployment = doc;
      }
    }
  }

  if (!runSelfTest) {
    // run_validate.sh's check of a broken manifest: only the documents' own errors.
  } else if (!deployment) {
    console.error('k8s-validate: FAILED: the self-test needs a valid Deployment among the manifests');
    failed++;
  } else {
    for (const f of selfTest(deployment)) {
      console.error(`k8s-validate: FAILED: self-test: ${f}`);
      failed++;
    }
  }
  console.log(`k8s-validate: ${files.length} files, ${documents} documents, ${failed} failures`);
  process.exit(failed ? 1 : 0);
}

main();
