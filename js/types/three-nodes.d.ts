// three's node entries for the type check of src/ (tsconfig.json): the devDependency's types (@types/three
// 0.160, the oldest three the WebGL entry supports) have no 'three/webgpu' or 'three/tsl', which the WebGPU
// entry imports from three r184 on; they are checked as `any` here.
declare module 'three/webgpu';
declare module 'three/tsl';
