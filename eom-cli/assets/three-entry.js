// The parts of three.js the animation page uses (bundled by bundle.sh).
export {
  Scene, PerspectiveCamera, WebGLRenderer, Group, Mesh, Line, LineSegments,
  SphereGeometry, CylinderGeometry, BoxGeometry, BufferGeometry, Float32BufferAttribute,
  MeshStandardMaterial, MeshBasicMaterial, LineBasicMaterial, AmbientLight, DirectionalLight,
  GridHelper, AxesHelper, ArrowHelper, Vector3, Quaternion, Color, Box3, Sphere,
} from 'three';
export { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
